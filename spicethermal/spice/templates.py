"""The one jinja2 environment: SPICE libraries, test benches and the HTML reports.

Templates live in the repository's ``templates/`` folder (``lib/`` for ``.lib`` files,
``bench/`` for test benches, ``report/`` for HTML), shipped in the wheel as
``spicethermal/_templates``. Undefined variables are errors (``StrictUndefined``); HTML
templates (``*.html.j2``) are autoescaped, SPICE text never is.

>>> env = environment()
>>> env.from_string("{{ x }}").render(x="<R1>")            # SPICE text: as written
'<R1>'
>>> env.autoescape("report/index.html.j2"), env.autoescape("lib/ngspice.lib.j2")
(True, False)
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

from ..effects.spice import number

if TYPE_CHECKING:  # pragma: no cover
    import jinja2

#: File-name endings of the templates that are autoescaped (HTML).
AUTOESCAPED = ("html.j2", "html")


def template_dir() -> Path:
    """The folder that holds the templates.

    Returns
    -------
    Path
        ``spicethermal/_templates`` in an installed wheel, else the repository's
        ``templates/`` beside the package.

    Examples
    --------
    >>> (template_dir() / "lib").is_dir()
    True
    """
    package = Path(__file__).resolve().parents[1]  # the spicethermal package
    packaged = package / "_templates"
    if packaged.is_dir():
        return packaged
    return package.parent / "templates"


@lru_cache(maxsize=1)
def environment() -> jinja2.Environment:
    """The jinja2 environment every template is rendered with.

    Returns
    -------
    jinja2.Environment
        Loads from :func:`template_dir`; ``StrictUndefined``; autoescape for ``*.html.j2``
        only; trailing newlines kept; ``fmt`` (a number in SPICE syntax, full precision) as a
        global.

    Examples
    --------
    >>> environment().from_string("R1 a b {{ fmt(r) }}").render(r=0.1)
    'R1 a b 0.1'
    """
    import jinja2

    env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(template_dir())),
                             undefined=jinja2.StrictUndefined, keep_trailing_newline=True,
                             autoescape=jinja2.select_autoescape(
                                 enabled_extensions=AUTOESCAPED, disabled_extensions=(),
                                 default_for_string=False, default=False))
    env.globals["fmt"] = number
    return env
