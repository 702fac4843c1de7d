"""The fastest safe drive of the thermopneumatic actuator.

:func:`spicethermal.drive.optimize.optimize_drive` is the entry point; it returns a
:class:`spicethermal.drive.result.DriveResult`. Nothing is imported here, so that importing
the package stays light.
"""
