r"""``AmigoBot-v0``: point H of an AmigoBot follows a path, steered by the two wheel rates.

The environment is a thin stateful shell over the pure, batched functions of
:mod:`amigo_gym.task.v0` (observation, reward, start, end), :mod:`amigo_gym.model.kinematics` (the exact
step) and :mod:`amigo_gym.paths`. :class:`AmigoBotEnv` holds one robot; the native vector
environment :class:`amigo_gym.envs.AmigoBotVectorEnv` holds ``N`` and calls the same functions.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields, replace
from typing import Any, SupportsFloat

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from amigo_gym.envs.base import (
    RESET_OPTIONS,
    AmigoBotBase,
    ObsArray,
    box_spaces,
    check_kernel,
    one_robot,
    parse_pose_option,
)
from amigo_gym.model.kinematics import h_position
from amigo_gym.model.params import EnvParams, RobotParams
from amigo_gym.paths import CirclePath, ManoeuvrePath, make_path
from amigo_gym.sim import fast
from amigo_gym.task import v0 as task

__all__ = ["ENV_SETTINGS", "RESET_OPTIONS", "AmigoBotEnv", "make_env_params", "make_spaces", "parse_pose_option"]

Array = NDArray[np.float64]

#: names of the task settings accepted as keywords by the environments (every ``EnvParams`` field)
ENV_SETTINGS: tuple[str, ...] = tuple(f.name for f in fields(EnvParams))

_np_array = np.array
#: the values of the single env's ``kernel`` keyword
SINGLE_KERNELS = fast.KERNELS


def _robot_params(owner: str, robot: RobotParams | Mapping[str, Any]) -> RobotParams:
    """A :class:`RobotParams`, or one made from a mapping of its field names (``TypeError`` on others)."""
    if isinstance(robot, RobotParams):
        return robot
    if not isinstance(robot, Mapping):
        raise TypeError(f"{owner}: robot must be a RobotParams or a mapping of its fields, got {type(robot).__name__}")
    names = {f.name for f in fields(RobotParams)}
    bad = sorted(str(k) for k in robot if k not in names)
    if bad:
        raise TypeError(f"{owner}: unknown robot field(s) {bad}; allowed: {', '.join(sorted(names))}")
    return RobotParams(**robot)


def _env_params(owner: str, params: EnvParams | Mapping[str, Any] | None) -> EnvParams:
    """An :class:`EnvParams`, or one made from a mapping of its field names (``robot`` may be a mapping too)."""
    if params is None:
        return EnvParams()
    if isinstance(params, EnvParams):
        return params
    if not isinstance(params, Mapping):
        raise TypeError(f"{owner}: params must be an EnvParams or a mapping of its fields, got {type(params).__name__}")
    bad = sorted(str(k) for k in params if k not in ENV_SETTINGS)
    if bad:
        raise TypeError(f"{owner}: unknown params field(s) {bad}; allowed: {', '.join(ENV_SETTINGS)}")
    kw = dict(params)
    if "robot" in kw:
        kw["robot"] = _robot_params(owner, kw["robot"])
    return EnvParams(**kw)


def make_env_params(
    owner: str,
    params: EnvParams | Mapping[str, Any] | None = None,
    robot: RobotParams | Mapping[str, Any] | None = None,
    **settings: Any,
) -> EnvParams:
    """Task settings from the keywords of ``gym.make`` / ``gym.make_vec``.

    Every configuration keyword accepts a plain mapping as well as its dataclass, so that the settings
    survive ``EnvSpec.to_json`` / ``from_json`` and rl-zoo's ``--env-kwargs``.

    Args:
        owner: name of the caller, for error messages.
        params: a complete :class:`EnvParams`, or a mapping of its field names to values (``robot``
            inside it may be a mapping too); defaults if ``None``.
        robot: a :class:`RobotParams`, or a mapping of its field names to values (e.g. from a YAML file).
        **settings: any other :class:`EnvParams` field (``dt``, ``radius``, ``speed``, ...); they
            override the fields of ``params``.

    Raises:
        TypeError: on an unknown keyword or field, or a ``params`` / ``robot`` of another type.
        ValueError: on a bad value (from :class:`EnvParams` / :class:`RobotParams`, naming the field and range).
    """
    unknown = sorted(k for k in settings if k not in ENV_SETTINGS)
    if unknown:
        allowed = ", ".join(("params", *ENV_SETTINGS))
        names = ", ".join(map(repr, unknown))
        raise TypeError(f"{owner} got unexpected keyword argument(s) {names}; allowed: {allowed}")
    base = _env_params(owner, params)
    if robot is not None:
        settings["robot"] = _robot_params(owner, robot)
    elif "robot" in settings:
        settings["robot"] = _robot_params(owner, settings["robot"])
    return replace(base, **settings) if settings else base


def make_spaces(params: EnvParams) -> tuple[spaces.Box, spaces.Box]:
    """The action and observation spaces of one robot (both environments; the vector env batches them).

    Action ``Box(-1, 1, (2,), float32)``; observation ``Box(low, high, (obs_dim,), float32)`` with the
    bounds of :func:`amigo_gym.task.v0.obs_bounds`.
    """
    return box_spaces(task.obs_bounds(params))


class AmigoBotEnv(AmigoBotBase):
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

    ``Box(low, high, (8 + len(preview),), float32)`` (bounds from :func:`amigo_gym.task.v0.obs_bounds`).
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

    Every setting is a keyword of ``gym.make("AmigoBot-v0", ...)``: any field of
    :class:`amigo_gym.EnvParams` (``dt``, ``radius``, ``speed``, ``direction``, ``path``,
    ``straight_length``, ``termination_distance``, ``init_position_noise``, ``init_heading_noise``,
    ``error_scale``, ``preview``, ``sigma_track``, ``sigma_speed``, ``sigma_smooth``,
    ``smooth_weight``), ``robot`` (a :class:`amigo_gym.RobotParams` or a dict of its fields),
    ``params`` (a whole ``EnvParams`` or a dict of its fields; other keywords override its fields) and ``render_mode``
    (``"human"`` or ``"rgb_array"``), and ``kernel``, how the step is computed (never what: the results are the
    same bits): ``"auto"`` (the default: the compiled step when numba is installed, the extra
    ``amigo_gym[fast]``, unless ``AMIGO_GYM_KERNEL=numpy``), ``"numpy"`` (the reference, Python floats) or
    ``"numba"``. Unknown keywords raise ``TypeError``, bad values
    ``ValueError`` naming the field and its range.

    ```python
    import gymnasium as gym
    import amigo_gym  # registers AmigoBot-v0

    env = gym.make("AmigoBot-v0", dt=0.05, radius=1.5, speed=0.3, max_episode_steps=800)
    ```

    ## Version History

    * v0: initial version.
    """

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        params: EnvParams | Mapping[str, Any] | None = None,
        robot: RobotParams | Mapping[str, Any] | None = None,
        kernel: str = "auto",
        **settings: Any,
    ) -> None:
        owner = type(self).__name__
        check_kernel(owner, kernel, SINGLE_KERNELS)
        self.params: EnvParams = make_env_params(owner, params, robot, **settings)
        p = self.params
        self._init_base(render_mode, p.dt, make_spaces(p))
        self.path: CirclePath | ManoeuvrePath = make_path(p)
        self._k = task.task_constants(p)
        rate1, rate2 = task.initial_wheel_rates(p).tolist()
        self._initial_state = task.State(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, rate1, rate2)
        # the compiled step (kernel="numba", or "auto" with numba installed): the state lives in its buffer
        self._st: task.State = self._initial_state
        self._fast: fast.SingleStep | None = None
        if fast.use_fast_path(None if kernel == "auto" else kernel == "numba"):
            self._fast = fast.SingleStep(self._k, self.path)
        # state (set by reset): plain scalars, stepped by the same column functions as the vector env
        self._state = self._initial_state
        self._steps = 0

    # ------------------------------------------------------------------ state access
    @property
    def _state(self) -> task.State:
        """The robot's state: Python floats (in the compiled step's buffer when it runs)."""
        if self._fast is not None:
            return task.State(*self._fast.state())
        return self._st

    @_state.setter
    def _state(self, value: task.State) -> None:
        self._st = value
        if self._fast is not None:
            self._fast.set_state(value)

    @property
    def pose(self) -> Array:
        """Current pose ``(x_A [m], y_A [m], beta [rad])``, a copy."""
        st = self._state
        return np.array((st.x, st.y, st.beta))

    @property
    def wheel_rates(self) -> Array:
        """Wheel rates applied during the last step (at reset: the initial rates) [rad/s], a copy."""
        return np.array((self._state.rate1, self._state.rate2))

    @property
    def time(self) -> float:
        """Time since reset [s]: ``steps * dt``."""
        return self._steps * self.params.dt

    # ------------------------------------------------------------------ the task's hooks (AmigoBotBase)
    def _begin(self, pose_opt: Array | None) -> tuple[ObsArray, dict[str, Any]]:
        """The start state (a drawn pose, or ``pose_opt``), its observation and info."""
        if pose_opt is not None:
            pose = pose_opt
        else:
            u = self.np_random.uniform(-1.0, 1.0, size=3)
            pose = task.start_pose(u, self.params, self.path)
        x, y, beta = pose.tolist()
        self._state = self._initial_state._replace(x=x, y=y, beta=beta)
        self._steps = 0
        out = task.reset_columns(self._k, self.path, self._state, minimal=True)
        return np.array(out.obs, dtype=np.float32), self._info(out)

    def _advance(self, a1: float, a2: float) -> tuple[ObsArray, SupportsFloat, bool, dict[str, Any]]:
        """Hold the wheel rates ``(a1, a2) * w_max`` for ``dt``: the step's observation, reward, end and info."""
        if self._fast is not None:
            return self._step_fast(a1, a2)
        st = self._state
        if type(st.x) is float and type(st.beta) is float:  # floats (always, after reset): one flat function
            state, out = task.step_float(self._k, self.path, st, a1, a2)
        else:
            state, out = task.step_columns(self._k, self.path, st, a1, a2, minimal=True)
        self._state = st = task.bound_heading(state)
        self._steps += 1
        if type(st.x) is float:  # task.info_columns in the single env's types, as a record (task.record_info)
            t = out.terms
            e = float(out.closest.cross_track_error)
            row = [st.x, st.y, st.beta, out.h_x, out.h_y, e, st.rate1, st.rate2, st.alpha1, st.alpha2]
            values = [*row, float(st.alpha3), float(t[0]), float(t[1]), float(t[2]), float(t[3])]
            # the four info arrays are views of one new array (one allocation instead of four)
            info = task.record_info(_np_array(row), values, float(self._steps * self._k.dt))
        else:
            info = self._info(out)
        return np.array(out.obs, dtype=np.float32), float(out.reward), bool(out.terminated), info

    def _step_fast(self, a1: float, a2: float) -> tuple[ObsArray, SupportsFloat, bool, dict[str, Any]]:
        """:meth:`_advance` by the compiled kernel (:class:`amigo_gym.sim.fast.SingleStep`): the same results, bit
        for bit."""
        fs = self._fast
        assert fs is not None
        self._steps += 1
        return fs.env_step(a1, a2, float(self._steps * self._k.dt))

    def _info(self, out: task.Outcome) -> dict[str, Any]:
        cols = task.info_columns(self._state, out, self._steps * self._k.dt)
        return {key: one_robot(value) for key, value in cols.items()}

    def _render_state(self) -> dict[str, Any]:
        st = self._state
        return {
            "pose": self.pose,
            "wheel_angles": np.array((st.alpha1, st.alpha2)),
            "time": self.time,
            "cross_track_error": self._last_error(),
        }

    def _last_error(self) -> float:
        return float(self.path.project(h_position(self.pose, self.params.robot)).cross_track_error)
