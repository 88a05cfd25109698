"""The environments' ``spec`` with its keywords in JSON form (dataclasses as mappings, tuples as lists), so that
``EnvSpec.from_json(spec.to_json())`` equals it; keywords JSON cannot hold stay as given."""

from __future__ import annotations

import dataclasses
import json
from typing import Any

from gymnasium.envs.registration import EnvSpec


def _plain(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: getattr(value, f.name) for f in dataclasses.fields(value)}
    raise TypeError(type(value).__name__)


def json_kwargs(kwargs: dict[str, Any]) -> dict[str, Any]:
    """``kwargs`` as a JSON round trip gives them back (dataclasses as mappings, tuples as lists), or unchanged when
    JSON cannot hold them (objects, NaN or infinities)."""
    try:
        text = json.dumps(kwargs, default=_plain, allow_nan=False)
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
            value = dataclasses.replace(value, kwargs=json_kwargs(self._spec_kwargs(value.kwargs)))
        self._json_spec = value

    def _spec_kwargs(self, kwargs: dict[str, Any]) -> dict[str, Any]:
        return kwargs  # what a subclass stores of the keywords, before the JSON form
