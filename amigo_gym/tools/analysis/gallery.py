"""``amigo-gym gallery``: a picture of every AmigoBot-v1 path family, driven by the analytic policy.

For each family of :data:`GALLERY`, the last frame (``render_mode="rgb_array"``) of one episode of ``AmigoBot-v1``
with :class:`amigo_gym.policies.AnalyticTrackingPolicy`, written as ``<out>/v1_<family>.png``.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from amigo_gym.envs.rendering import headless
from amigo_gym.io import atomic_save
from amigo_gym.policies import AnalyticTrackingPolicy
from amigo_gym.tools.options import cli, run_command
from amigo_gym.tools.plots import pyplot

#: name -> (keyword arguments of gym.make("AmigoBot-v1"), steps)
GALLERY: dict[str, tuple[dict[str, Any], int]] = {
    "circle": ({"path": "circle", "radius": 1.0, "speed": 0.3}, 260),
    "manoeuvre": ({"path": "manoeuvre", "speed_profile": "trapezoid", "profile_duration": 30.0}, 300),
    "figure8": ({"path": "figure8", "speed": 0.3}, 600),
    "lane_change": ({"path": "lane_change", "speed": 0.3}, 200),
    "random": ({"path": "random", "speed": 0.3}, 600),
    "figure8_hard": ({"path": "figure8", "speed": 0.3, "randomize": "hard"}, 600),
}


def render_family(kwargs: dict[str, Any], steps: int, seed: int = 0) -> tuple[np.ndarray[Any, Any], float]:
    """The last frame of one episode with the analytic policy and H's largest error after 5 s [m]."""
    env = gym.make("AmigoBot-v1", render_mode="rgb_array", max_episode_steps=steps, **kwargs)
    policy = AnalyticTrackingPolicy(env.unwrapped.params)  # type: ignore[attr-defined]
    obs, _ = env.reset(seed=seed)
    state, worst = None, 0.0
    for t in range(steps):
        action, state = policy.predict(obs[None, :], state, np.array([t == 0]))
        obs, _, term, trunc, info = env.step(action[0])
        if t * env.unwrapped.params.dt > 5.0:  # type: ignore[attr-defined]
            worst = max(worst, abs(info["cross_track_error"]))
        if term or trunc:
            break
    frame = env.render()
    env.close()
    assert isinstance(frame, np.ndarray)
    return frame, worst


@dataclass(frozen=True)
class GallerySettings:
    __doc__ = f"""Options of ``amigo-gym gallery``, each the option of the same name.

    Attributes:
        out: output folder [dir].
        only: families to draw [names] (default: all, {", ".join(GALLERY)}).
    """

    out: str = "docs/figures"
    only: list[str] | None = field(default=None, metadata=cli(nargs="*"))

    def validate(self) -> None:
        """Raise ``ValueError`` naming an unknown family and the known ones."""
        for name in self.only or ():
            if name not in GALLERY:
                raise ValueError(f"--only: unknown family {name!r}; choose from {', '.join(GALLERY)}")


def _draw(args: GallerySettings) -> None:
    headless()
    for name in args.only or GALLERY:
        frame, worst = render_family(*GALLERY[name])
        target = Path(args.out) / f"v1_{name}.png"
        atomic_save(functools.partial(pyplot().imsave, arr=frame), target, parents=True)
        print(f"{target}: max |e| of H after 5 s = {worst:.3g} m", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """``amigo-gym gallery [--out DIR] [--only NAME ...]`` (module docstring)."""
    return run_command(GallerySettings, _draw, argv, "amigo-gym gallery", __doc__.splitlines()[0])
