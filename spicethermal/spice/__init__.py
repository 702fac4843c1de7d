"""SPICE text: the one template environment, .lib writers per dialect, test benches, ngspice
runners."""
