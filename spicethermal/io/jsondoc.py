"""The one serialisation convention: ``to_dict()``/``from_dict()`` for JSON-ready data,
``to_json()``/``from_json()`` for the JSON text (strict: no NaN, see
:func:`spicethermal.io.files.dumps_json`).

A class defines ``to_dict()`` (and ``from_dict()`` when it can be rebuilt from its document)
and inherits the text forms from :class:`JsonDocument`.

>>> from dataclasses import dataclass
>>> @dataclass
... class Point(JsonDocument):
...     x: float
...     def to_dict(self):
...         return {"x": self.x}
...     @classmethod
...     def from_dict(cls, data):
...         return cls(data["x"])
>>> Point(1.5).to_json(indent=None)
'{"x": 1.5}'
>>> Point.from_json('{"x": 2.0}')
Point(x=2.0)
"""

from __future__ import annotations

import json
from typing import Any

from .files import dumps_json


class JsonDocument:
    """Mixin: :meth:`to_json` and :meth:`from_json` from a class's ``to_dict``/``from_dict``."""

    def to_dict(self) -> dict[str, Any]:  # pragma: no cover - every subclass defines it
        """The object as JSON-ready data.

        Returns
        -------
        dict
            Plain dicts, lists, strings, numbers, booleans and None.
        """
        raise NotImplementedError

    def to_json(self, indent: int | None = 2) -> str:
        """:meth:`to_dict` as strict JSON text.

        Parameters
        ----------
        indent : int or None
            Indentation (None: one line).

        Returns
        -------
        str
            The JSON text.
        """
        return dumps_json(self.to_dict(), indent=indent)

    @classmethod
    def from_json(cls, text: str) -> Any:
        """Rebuild an object from the text :meth:`to_json` wrote.

        Parameters
        ----------
        text : str
            JSON text.

        Returns
        -------
        object
            ``cls.from_dict(json.loads(text))``.
        """
        return cls.from_dict(json.loads(text))
