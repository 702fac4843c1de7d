"""Plausibility of a result: a warning when an input implies a temperature no device reaches.

A junction rise of thousands of kelvin is not an operating point but a typo (``--power 94meg``
for 94 mW) or a wrong model; the commands print :func:`implausible_rise` on stderr and go on.
"""

from __future__ import annotations

__all__ = ["MAX_PLAUSIBLE_RISE_K", "implausible_rise"]

#: A rise above this is beyond any device in operation (silicon melts 1389 K above 25 °C).
MAX_PLAUSIBLE_RISE_K = 1000.0


def implausible_rise(rise_k: float, inputs: str) -> str | None:
    """A one-line warning when ``rise_k`` is beyond any device, else None.

    Parameters
    ----------
    rise_k : the largest junction rise a result implies, K.
    inputs : what the rise comes from, as the user gave it (``--power 9.4e+07 W``).

    Returns
    -------
    str or None : the warning, naming the rise and ``inputs``.

    Examples
    --------
    >>> implausible_rise(2.76, "--power 0.094 W") is None
    True
    >>> implausible_rise(2.76e9, "--power 9.4e+07 W").split(": ")
    ['a peak rise of 2.76e+09 K is not a device in operation (over 1000 K)', \
'check --power 9.4e+07 W and the model']
    """
    if not rise_k > MAX_PLAUSIBLE_RISE_K:
        return None
    return (f"a peak rise of {rise_k:.3g} K is not a device in operation (over "
            f"{MAX_PLAUSIBLE_RISE_K:g} K): check {inputs} and the model")
