"""Arrays of heated devices: the N-port thermal network of actuators on a common substrate.

A tactile display is many actuators a few millimetres apart; each heats its neighbours. This
package holds the N-port model (:mod:`.model`, :mod:`.modal`), its fit to "heat one, read
all" measurements (:mod:`.data`, :mod:`.ansatz`, :mod:`.fit`) and the array drive
(:mod:`.braille`, :mod:`.drive`, :mod:`.refresh`, :mod:`.check`). An array of one port is
the single-device model (:meth:`.model.ArrayModel.from_thermal_model`).
"""
