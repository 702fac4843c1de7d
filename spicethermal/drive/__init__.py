"""The fastest safe drive of the thermopneumatic actuator."""
