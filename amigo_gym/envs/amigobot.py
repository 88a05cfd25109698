r"""``AmigoBot-v0``: point H of an AmigoBot follows a path, steered by the two wheel rates.

AmigoBot-v0 is a configuration of the one robot and task: :class:`AmigoBotEnv` and :class:`AmigoBotVectorEnv` are
the AmigoBot-v1 classes built with :meth:`amigo_gym.task.v1.TrackingParams.v0` of AmigoBot-v0's keywords
(``env.params``), reporting v0's info keys.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import fields
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode
from numpy.typing import NDArray

from amigo_gym.envs.amigobot_v1 import AmigoBotV1Env
from amigo_gym.envs.base import TRAIL_LENGTH
from amigo_gym.envs.spec import JsonSpecMixin
from amigo_gym.envs.vector_v1 import AmigoBotV1VectorEnv
from amigo_gym.model.kinematics import h_position
from amigo_gym.model.params import RobotParams
from amigo_gym.task.v0 import V0_DEFAULTS
from amigo_gym.task.v1 import TrackingParams, v0_settings

Array = NDArray[np.float64]


def _fields(owner: str, what: str, value: Any, names: Collection[str]) -> dict[str, Any]:
    """The mapping ``value`` as a dict (``TypeError`` on another type or a name not in ``names``)."""
    if not isinstance(value, Mapping):
        kinds = {"params": "AmigoBot-v0's TrackingParams.v0(...) or a mapping of its keywords"}
        kind = kinds.get(what, "a RobotParams or a mapping of its fields")
        raise TypeError(f"{owner}: {what} must be {kind}, got {type(value).__name__}")
    if bad := sorted(str(k) for k in value if k not in names):
        raise TypeError(f"{owner}: unknown {what} field(s) {bad}; allowed: {', '.join(names)}")
    return dict(value)


def make_env_params(
    owner: str,
    params: TrackingParams | Mapping[str, Any] | None = None,
    robot: RobotParams | Mapping[str, Any] | None = None,
    **settings: Any,
) -> TrackingParams:
    """AmigoBot-v0's task (:meth:`amigo_gym.task.v1.TrackingParams.v0`) from the keywords of ``gym.make`` /
    ``gym.make_vec`` of ``owner`` (named in errors): ``params`` (an AmigoBot-v0 env's ``params`` or a mapping of its
    settings, as ``EnvSpec`` JSON and rl-zoo's ``--env-kwargs`` hold them), ``robot`` (a :class:`RobotParams` or a
    mapping of its fields) and any other setting (overriding ``params``'). Raises ``TypeError`` (an unknown keyword
    or field, a ``params`` / ``robot`` of another type) or ``ValueError`` (:func:`amigo_gym.task.v0.check_v0`).
    """
    if unknown := sorted(k for k in settings if k not in V0_DEFAULTS):
        allowed = ", ".join(("params", *V0_DEFAULTS))
        names = ", ".join(map(repr, unknown))
        raise TypeError(f"{owner} got unexpected keyword argument(s) {names}; allowed: {allowed}")
    given = (v0_settings(params) or params) if isinstance(params, TrackingParams) else params
    kw = ({} if given is None else _fields(owner, "params", given, V0_DEFAULTS)) | settings
    if robot is not None:
        kw["robot"] = robot
    if not isinstance(kw.get("robot", V0_DEFAULTS["robot"]), RobotParams):
        kw["robot"] = RobotParams(**_fields(owner, "robot", kw["robot"], [f.name for f in fields(RobotParams)]))
    return TrackingParams.v0(**kw)


class _V0Spec(JsonSpecMixin):
    """``spec`` whose ``params``, if a ``TrackingParams``, is kept as AmigoBot-v0's settings (a JSON mapping)."""

    def _spec_kwargs(self, kwargs: dict[str, Any]) -> dict[str, Any]:
        given = kwargs.get("params")
        return {**kwargs, "params": v0_settings(given)} if isinstance(given, TrackingParams) else kwargs


class AmigoBotEnv(_V0Spec, AmigoBotV1Env):
    r"""AmigoBot path tracking: drive point H of a differential-drive robot along a circle.

    ## Description

    The AmigoBot is a small differential-drive robot (ActivMedia / Adept MobileRobots) with two
    driven wheels and a self-aligning castor. Its kinematics follow the D–H model of the seed
    paper, corrected as in ``docs/model.md``: the pose is ``(x_A, y_A, beta)``, A the midpoint
    of the drive axle, ``beta`` the heading; point H sits ``l3 = 0.08 m`` ahead of A. The task is
    the paper's inverse problem turned into control: keep H on the path (by default the paper's
    circle, eq. 6: radius ``R = 1 m`` through the origin, tangent to x0 there, turning left) while A
    drives at the reference speed ``v_ref = 0.2 m/s``. The wheel rates are held over each control
    period ``dt`` and the pose advances by the exact arc of the rolling constraints (no Euler
    step); the analytic inverse solution therefore follows the circle exactly in the environment.
    ``path="manoeuvre"`` selects the paper's manoeuvre instead: a straight segment along x0, then
    the circle.

    ## Action Space

    ``Box(-1, 1, (2,), float32)``: the wheel rates normalised by ``w_max = robot.max_wheel_rate``
    (15 rad/s: the AmigoBot-SH's 0.75 m/s over r = 0.05 m). Values outside [-1, 1] are clipped;
    NaN, infinities and wrong shapes raise ``ValueError``. float64 actions are applied exactly (no
    cast through float32).

    | Num | Action                              | Min | Max | Unit after scaling |
    |-----|-------------------------------------|-----|-----|--------------------|
    | 0   | ``alpha1dot / w_max``, wheel 1 (right) | -1  | 1   | rad/s              |
    | 1   | ``alpha2dot / w_max``, wheel 2 (left)  | -1  | 1   | rad/s              |

    ## Observation Space

    ``Box(low, high, (8 + len(preview),), float32)`` (bounds from :func:`amigo_gym.task.v0.obs_bounds_of`).
    ``e`` is H's signed cross-track error (positive left of the path), ``psi = wrap(beta - theta)``
    the heading minus the path tangent at H's closest point, ``kappa`` the signed path curvature.
    Every reader decodes it by the names of :func:`amigo_gym.task.v0.obs_names` (index by
    :func:`amigo_gym.task.v0.obs_index`). With the default ``preview = (0.2, 0.4)`` the shape is ``(10,)``:

    | Num | Name                  | Observation                              | Min                 | Max               |
    |-----|-----------------------|------------------------------------------|---------------------|-------------------|
    | 0   | ``cross_track_error`` | ``e / error_scale`` (clipped)            | ``-2 d_term / e_s`` | ``2 d_term / e_s``|
    | 1   | ``sin_heading_error`` | ``sin(psi)``                             | -1                  | 1                 |
    | 2   | ``cos_heading_error`` | ``cos(psi)``                             | -1                  | 1                 |
    | 3   | ``curvature``         | ``kappa(s_H) l3``                        | -1                  | 1                 |
    | 4   | ``curvature_ahead_1`` | ``kappa(s_H + 0.2 m) l3`` (preview)      | -1                  | 1                 |
    | 5   | ``curvature_ahead_2`` | ``kappa(s_H + 0.4 m) l3`` (preview)      | -1                  | 1                 |
    | 6   | ``wheel_rate_1``      | ``alpha1dot / w_max`` (applied, wheel 1) | -1                  | 1                 |
    | 7   | ``wheel_rate_2``      | ``alpha2dot / w_max`` (applied, wheel 2) | -1                  | 1                 |
    | 8   | ``speed_error``       | ``(v_A - v_ref) / v_max``                | -2                  | 2                 |
    | 9   | ``reference_speed``   | ``v_ref / v_max``                        | 0                   | 1                 |

    ``d_term = termination_distance`` (0.25 m), ``e_s = error_scale`` (0.05 m): row 0 lies in [-10, 10].

    ## Rewards

    The product of four terms, each in [0, 1] (:data:`amigo_gym.task.v0.REWARD_TERMS`), so each step
    earns at most 1 and an episode of ``n`` steps at most ``n``:

    ``r = track * speed * heading * smooth`` with

    * ``track = exp(-|e| / sigma_track)``
    * ``speed = exp(-|v_A - v_ref| / sigma_speed)``
    * ``heading = (1 + cos(psi - psi_ss)) / 2``
    * ``smooth = 1 - w_s (1 - exp(-(|da| / sigma_smooth)^2))``

    with ``psi_ss = -asin(kappa l3)`` the heading error of the exact steady state and ``da`` the
    change of the normalised wheel-rate command. The terms are in ``info["reward_terms"]``.
    Driving the exact inverse solution earns more than 99 % of the maximum; standing still,
    spinning in place or driving the circle the wrong way earn less than 20 %.

    ## Starting State

    H starts at the path's start point (the origin) plus a uniform perturbation of
    ``±init_position_noise`` (0.02 m) per axis, heading along the path tangent (0) plus
    ``±init_heading_noise`` (0.1 rad); A is ``l3`` behind H. Wheel rates start at the straight
    roll at the reference speed, ``v_ref / r`` (4 rad/s); wheel angles at 0.
    ``reset(options={"pose": (x_A, y_A, beta)})`` sets an exact start pose instead.

    ## Episode End

    * Termination: ``|e| > termination_distance`` (0.25 m).
    * Truncation: after 400 steps (40 s at dt = 0.1 s, 1.28 laps of the default circle), by the
      ``TimeLimit`` of the registration (``max_episode_steps`` of ``gym.make``).

    ## Info

    At every ``reset`` and ``step``: ``pose`` (float64 (3,): x_A, y_A [m], beta [rad], unwrapped),
    ``h_position`` ((2,) [m]), ``cross_track_error`` (float, signed, [m]), ``wheel_rates`` (applied
    ``(alpha1dot, alpha2dot)`` [rad/s] (2,)), ``wheel_angles`` (``(alpha1, alpha2)`` [rad] (2,)),
    ``castor_angle`` (the castor wheel's rolling angle ``alpha3`` [rad]), ``reward_terms`` (dict of
    floats; at reset, the terms of the start state with the smoothness term at 1) and ``time`` [s].

    ## Arguments

    Every setting is a keyword of ``gym.make("AmigoBot-v0", ...)``: any of AmigoBot-v0's settings
    (:func:`amigo_gym.task.v0.check_v0`: ``dt``, ``radius``, ``speed``, ``direction``, ``path``,
    ``straight_length``, ``termination_distance``, ``init_position_noise``, ``init_heading_noise``,
    ``error_scale``, ``preview``, ``sigma_track``, ``sigma_speed``, ``sigma_smooth``,
    ``smooth_weight``), ``robot`` (a :class:`amigo_gym.RobotParams` or a dict of its fields),
    ``params`` (an AmigoBot-v0 env's ``params`` or a dict of its settings; other keywords override them),
    ``render_mode`` (``"human"`` or ``"rgb_array"``), and ``kernel``, how the step is computed (never what: the
    results agree to 1e-9, ``tests/test_kernel_v1.py``): ``"auto"`` (the default: the compiled step when numba is
    installed, a core dependency where it ships wheels, unless ``AMIGO_GYM_KERNEL=numpy``), ``"numpy"`` (the
    reference, Python floats: :mod:`amigo_gym.task.v1`'s step with ideal actuators) or ``"numba"`` (the compiled
    step, :mod:`amigo_gym.sim.fast_v1`). Unknown keywords raise ``TypeError``, bad values ``ValueError`` naming the
    field and its range.

    ```python
    import gymnasium as gym
    import amigo_gym  # registers AmigoBot-v0

    env = gym.make("AmigoBot-v0", dt=0.05, radius=1.5, speed=0.3, max_episode_steps=800)
    ```

    ## Version History

    * v0: initial version.
    """

    #: points of H kept for the rendered trail (the most recent ones)
    trail_length: int = TRAIL_LENGTH
    _v0 = True

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        params: TrackingParams | Mapping[str, Any] | None = None,
        robot: RobotParams | Mapping[str, Any] | None = None,
        kernel: str = "auto",
        **settings: Any,
    ) -> None:
        p = make_env_params(type(self).__name__, params, robot, **settings)
        super().__init__(render_mode, params=p, kernel=kernel)

    @property
    def pose(self) -> Array:
        """Current pose ``(x_A [m], y_A [m], beta [rad])``, a copy."""
        st = self._current_state()
        return np.array((st.x, st.y, st.beta), dtype=np.float64)

    @property
    def wheel_rates(self) -> Array:
        """Wheel rates applied during the last step (at reset: the initial rates) [rad/s], a copy."""
        st = self._current_state()
        return np.array((st.w1, st.w2), dtype=np.float64)

    @property
    def time(self) -> float:
        """Time since reset [s]: ``steps * dt``."""
        return self._steps * self.params.dt

    def _render_state(self) -> dict[str, Any]:
        """AmigoBot-v1's, with H's cross-track error (drawn in the frame)."""
        out = super()._render_state()
        h = h_position(out["pose"], self.params.robot)
        out["cross_track_error"] = float(self.path.project(h).cross_track_error)
        return out


class AmigoBotVectorEnv(_V0Spec, AmigoBotV1VectorEnv):
    """``N`` AmigoBot-v0 tasks stepped as numpy batches: :class:`amigo_gym.envs.AmigoBotV1VectorEnv` (its arguments;
    ``max_episode_steps`` 400 from ``gym.make_vec``) on AmigoBot-v0's task, ``params``, ``robot``, ``**settings`` as
    for ``gym.make("AmigoBot-v0", ...)``. Spaces, seeds, reset options and infos as ``SyncVectorEnv`` of
    :class:`AmigoBotEnv` (docs/env_card.md, "Vector environment").
    """

    _v0 = True

    def __init__(
        self,
        num_envs: int = 1,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
        kernel: str = "auto",
        *,
        params: TrackingParams | Mapping[str, Any] | None = None,
        robot: RobotParams | Mapping[str, Any] | None = None,
        **settings: Any,
    ) -> None:
        p = make_env_params(type(self).__name__, params, robot, **settings)
        super().__init__(num_envs, max_episode_steps, render_mode, autoreset_mode, kernel, params=p)
        #: the path every robot follows (``params.path``)
        self.path: Any = p.path
