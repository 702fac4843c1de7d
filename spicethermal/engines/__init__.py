"""Simulation engines: the analytic periodic steady state and the ngspice/PySpice sweeps."""
