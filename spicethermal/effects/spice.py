"""What effect modules need to write their SPICE renderings: numbers in SPICE syntax.

A rendering is a dialect-neutral behavioural expression (``+ - * /``, ``EXP``, ``LOG`` (the
natural logarithm in ngspice and its PSPICE and LTspice modes), ``MAX``, ``MIN``, ``PWR``) that
:mod:`spicethermal.spice.lib` places in the dialect's behavioural element.
"""

from __future__ import annotations


def number(x: float) -> str:
    """A number in SPICE syntax with full double precision (no engineering suffixes).

    Parameters
    ----------
    x : float
        The value.

    Returns
    -------
    str
        Its shortest exact decimal form.

    >>> number(1e-4), number(146.0)
    ('0.0001', '146.0')
    """
    return repr(float(x))
