r"""TD3 with the low-pass filter inside its actor (``policy: LowPassMlpPolicy``): ``a = p + alpha (u - p)``.

``u = tanh(mlp(o))`` [normalised action units], ``p`` ``(N, 2)`` the previous command read from AmigoBot-v1's
observation (``previous_command_1``, ``_2``), ``alpha`` in (0, 1] (1: SB3's actor). The critic learns ``Q(o, a)`` of
the filtered action; the saved zip is the filtered policy (``alpha`` and the indices are its ``policy_kwargs``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3.td3.policies import Actor, TD3Policy

from amigo_gym.model.params import check_real
from amigo_gym.task.v1 import TrackingParams, obs_fields
from amigo_gym.tools.training.hyperparams import LOWPASS_POLICY as POLICY_NAME


def check_filter(filter_alpha: object, prev_index: object, obs_dim: int) -> tuple[float, tuple[int, int]]:
    """The checked ``(alpha, (i1, i2))``: ``alpha`` in (0, 1], two distinct indices in [0, ``obs_dim``)."""
    a = check_real("policy_kwargs", "filter_alpha", filter_alpha, 0.0, 1.0, low_open=True)
    idx = list(prev_index) if isinstance(prev_index, Sequence) and not isinstance(prev_index, str) else []
    ok = all(not isinstance(i, bool) and isinstance(i, int | np.integer) and 0 <= int(i) < obs_dim for i in idx)
    if not (ok and len(idx) == 2 and idx[0] != idx[1]):
        raise ValueError(
            f"policy_kwargs.prev_index must be two distinct observation indices in [0, {obs_dim}), got {prev_index!r}"
        )
    return a, (int(idx[0]), int(idx[1]))


class LowPassActor(Actor):
    """SB3's TD3 actor followed by the low-pass filter (``prev_index``: the observation indices of ``p``)."""

    def __init__(self, *args: Any, filter_alpha: float, prev_index: Sequence[int], **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.filter_alpha, self.prev_index = filter_alpha, tuple(prev_index)  # checked by LowPassTD3Policy
        self.register_buffer("_prev_idx", th.as_tensor(self.prev_index, dtype=th.long), persistent=False)

    def forward(self, obs: th.Tensor) -> th.Tensor:
        u = super().forward(obs)
        prev = obs.reshape(obs.shape[0], -1).index_select(1, self.get_buffer("_prev_idx")).to(u.dtype).clamp(-1.0, 1.0)
        out: th.Tensor = prev + self.filter_alpha * (u - prev)
        return out


class LowPassTD3Policy(TD3Policy):
    """SB3's ``TD3Policy`` with :class:`LowPassActor` actors; ``filter_alpha``, ``prev_index``: saved as
    ``policy_kwargs``. The action space must be ``Box(-1, 1)``."""

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Box,
        *args: Any,
        filter_alpha: float = 1.0,
        prev_index: Sequence[int] = (0, 1),
        **kwargs: Any,
    ) -> None:
        if not (
            isinstance(action_space, spaces.Box)
            and np.all(action_space.low == -1.0)
            and np.all(action_space.high == 1.0)
        ):
            raise ValueError(f"{POLICY_NAME}: the action space must be Box(-1, 1), got {action_space}")
        obs_dim = int(np.prod(observation_space.shape or (0,)))
        self.filter_alpha, self.prev_index = check_filter(filter_alpha, prev_index, obs_dim)
        super().__init__(observation_space, action_space, *args, **kwargs)

    def _get_constructor_parameters(self) -> dict[str, Any]:
        data = super()._get_constructor_parameters()
        data.update(filter_alpha=self.filter_alpha, prev_index=self.prev_index)
        return data

    def make_actor(self, features_extractor: Any = None) -> Actor:
        kw = self._update_features_extractor(self.actor_kwargs, features_extractor)
        return LowPassActor(**kw, filter_alpha=self.filter_alpha, prev_index=self.prev_index).to(self.device)


def policy_for(venv: Any, policy_kwargs: dict[str, Any] | None) -> tuple[type[LowPassTD3Policy], dict[str, Any]]:
    """The policy class and its ``policy_kwargs`` for a TD3 run on ``venv`` (an SB3 VecEnv of AmigoBot-v1)."""
    params = venv.get_attr("params")[0]
    if not isinstance(params, TrackingParams) or params.observation != "v1":
        got = "AmigoBot-v0's settings" if isinstance(params, TrackingParams) else type(params).__name__
        raise ValueError(f"{POLICY_NAME}: needs AmigoBot-v1 (its observation layout), got {got}")
    names = list(obs_fields(params))
    if "previous_command_1" not in names or "previous_command_2" not in names:
        raise ValueError(
            f"{POLICY_NAME}: the observation has no previous_command_1/_2 field (AmigoBot-v1's layout needed); "
            f"fields: {', '.join(names)}"
        )
    prev = (names.index("previous_command_1"), names.index("previous_command_2"))
    return LowPassTD3Policy, {**(policy_kwargs or {}), "prev_index": prev}
