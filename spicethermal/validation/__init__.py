"""An independent validation set for the diagnosis (issue 14, point 7).

Nothing here uses the project's own physics (:mod:`spicethermal.effects`,
:mod:`spicethermal.fit.effectfit`, :mod:`spicethermal.model`, :mod:`spicethermal.engines.pwm`, the
bench plant): :mod:`.network` integrates a nonlinear Cauer ladder on its own, :mod:`.periodic` finds
PWM periodic steady states by shooting, :mod:`.measure` applies the bench's artefacts and
writes ``spicethermal-bundle/1`` bundles through :class:`spicethermal.io.bundle.Bundle`,
:mod:`.cases` holds the catalogue of cases with their truth, and :mod:`.detect` marks which
ones are detectable at all.
"""
