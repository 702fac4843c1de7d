"""An independent validation generator for the diagnosis.

Nothing here uses the project's own physics (:mod:`spicethermal.effects`,
:mod:`spicethermal.fit`, :mod:`spicethermal.model`, :mod:`spicethermal.engines.pwm`, the bench
plant): :mod:`.network` integrates a nonlinear Cauer ladder on its own with the temperature laws
and latent-heat bands of :mod:`.laws`, :mod:`.linear` holds linear devices of any shape,
:mod:`.periodic` finds PWM periodic steady states by shooting, :mod:`.measure` applies the
bench's artefacts and writes bundles through :class:`spicethermal.io.bundle.Bundle`,
:mod:`.cases` holds the device classes, the cases with their truth and acceptable verdicts, and
the fixed catalogue, :mod:`.draws` the random held-out draws over every class and kind of
physics, and :mod:`.detect` marks which cases are detectable at all.
"""
