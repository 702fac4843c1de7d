"""The measurement bench: protocol, pyserial client, and the simulated instrument.

* :mod:`.protocol` - framing, CRC and messages (pure functions; spec in firmware/PROTOCOL.md)
* :mod:`.client` - the pyserial client and the procedures
* :mod:`.session` - whole runs added to a bundle under its lock: :func:`.session.run_bench`
* :mod:`.plan` - what a run measures (:class:`.plan.Plan`, a preset per board);
  :mod:`.merge` - how its data sets join the bundle's, losing nothing
* :mod:`.simulator` - the firmware core (host build, via ctypes) driving a simulated plant
* :mod:`.protocol_sim` - the ``sim://`` pyserial URL handler
* :mod:`.plant`, :mod:`.devices` - the simulated device and its presets

Nothing here is imported by ``import spicethermal``; pyserial is imported when used.
"""
