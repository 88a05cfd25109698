"""The environments' ``spec`` with its keywords in JSON form: ``EnvSpec.from_json(spec.to_json())`` equals it.

``EnvSpec.to_json`` turns dataclasses into mappings and tuples into lists; :class:`JsonSpecMixin` stores the
keywords in that form already (the envs accept mappings and lists for every setting). Keywords JSON cannot hold
(a path object of your own) stay as given.
"""

from __future__ import annotations

import dataclasses
import json
from typing import Any

from gymnasium.envs.registration import EnvSpec


def _plain(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def json_kwargs(kwargs: dict[str, Any]) -> dict[str, Any]:
    """``kwargs`` as a JSON round trip gives them back (dataclasses as mappings, tuples as lists), or unchanged when
    JSON cannot hold them (objects, NaN or infinities)."""
    try:
        text = json.dumps(_plain(kwargs), allow_nan=False)
    except (TypeError, ValueError):
        return kwargs
    out: dict[str, Any] = json.loads(text)
    return out


class JsonSpecMixin:
    """``spec`` stored with its keywords in JSON form (:func:`json_kwargs`); set by ``make``/``make_vec``."""

    _json_spec: EnvSpec | None = None

    @property
    def spec(self) -> EnvSpec | None:
        """The environment's :class:`gymnasium.envs.registration.EnvSpec`, keywords in JSON form (None before set)."""
        return self._json_spec

    @spec.setter
    def spec(self, value: EnvSpec | None) -> None:
        if value is not None and isinstance(value.kwargs, dict):
            value = dataclasses.replace(value, kwargs=json_kwargs(value.kwargs))
        self._json_spec = value
