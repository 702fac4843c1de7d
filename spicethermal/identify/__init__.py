"""From a measurement to Zth(t): TSP calibration, cooling curves, early-time correction,
time-constant spectrum, structure functions."""
