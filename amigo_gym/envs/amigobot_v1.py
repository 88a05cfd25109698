r"""``AmigoBot-v1``: the real robot on many paths (actuator ramps, mismatch, slip, delay and noise, exactly
integrated), a stateful shell over the functions of :mod:`amigo_gym.task.v1`."""

from __future__ import annotations

import copy
import math
from collections import deque
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from amigo_gym.envs.base import RENDER_MODES, Array, ObsArray, box_spaces, check_reset_options, parse_pose_option
from amigo_gym.envs.rendering import Renderer
from amigo_gym.envs.spec import JsonSpecMixin
from amigo_gym.model.kinematics import advance_angle, body_velocity_of, castor_rate_float
from amigo_gym.model.randomization import StepNoise
from amigo_gym.sim import fast_v1
from amigo_gym.sim import layout_v1 as _L
from amigo_gym.task import v0 as task
from amigo_gym.task import v1 as tracking


def reference_record(w_max: float, st: tracking.State, out: tracking.Outcome, noise: StepNoise, castor: Any) -> Array:
    """The info record (:data:`amigo_gym.sim.layout_v1.RECORD_WIDTH`) of the reference's state, outcome and draws:
    ``(RECORD_WIDTH,)`` or ``(N, RECORD_WIDTH)``; ``w_max`` [rad/s] scales the command, ``castor`` [rad]."""
    track, speed, heading, smooth = out.terms
    cols = (
        st.x, st.y, st.beta, out.h_x, out.h_y, st.w1, st.w2, st.a1 * w_max, st.a2 * w_max, st.alpha1, st.alpha2,
        out.meas_x, out.meas_y, out.meas_beta, noise.slip1, noise.slip2, out.error, st.progress, out.v_true,
        out.v_ref, heading, out.end_of_path, out.terminated, castor, track, speed, np.nan, smooth, out.reward,
    )  # fmt: skip
    return np.stack(np.broadcast_arrays(*(np.asarray(c, dtype=np.float64) for c in cols)), axis=-1)


#: the info record's arrays as indices of its last axis; its scalars (``record[..., R_ERROR:]``) by index
_POSE, _H, _RATES, _COMMAND, _ANGLES, _MEASURED, _SLIP = (
    (..., r) for r in (_L.R_POSE, _L.R_H, _L.R_RATES, _L.R_COMMAND, _L.R_ANGLES, _L.R_MEASURED, _L.R_SLIP)
)
_E, _PROGRESS, _VT, _VREF, _HEADING, _END, _TERM, _CASTOR, _TRACK, _SPEED, _SMOOTH, _REWARD = (
    i - _L.R_ERROR for i in (_L.R_ERROR, _L.R_PROGRESS, _L.R_VT, _L.R_VREF, _L.R_HEADING, _L.R_END, _L.R_TERM,
                             _L.R_CASTOR, _L.R_TRACK, _L.R_SPEED, _L.R_SMOOTH, _L.R_REWARD))  # fmt: skip


def v0_record_info(record: Any, values: Any, time: Any) -> dict[str, Any]:
    """AmigoBot-v0's info (:func:`amigo_gym.task.v0.info_dict`) of info records, arguments as :func:`record_info`."""
    terms = (values[_TRACK], values[_SPEED], values[_HEADING], values[_SMOOTH])
    return task.info_dict(
        record[_POSE], record[_H], values[_E], record[_RATES], record[_ANGLES], values[_CASTOR], terms, time
    )


def record_info(
    record: Any,
    values: Any,
    time: Any,
    true_robot: dict[str, Any],
    delay: Any,
    end_of_path: Any,
    path: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """AmigoBot-v1's info (one robot's, or the vector env's compact infos) of info records.

    Args:
        record: ``(RECORD_WIDTH,)`` or ``(N, RECORD_WIDTH)``, a new array: the info's arrays are views of it.
        values: the record's scalars (``record[..., R_ERROR:]``): floats or ``(N,)`` views.
        time: time since the reset [s]; true_robot: ``{"r1", "r2", "l1"}`` [m]; delay [s]; end_of_path: floats
            or columns. path: the path's description (the single env's only), or None.
    """
    info = {
        "pose": record[_POSE],
        "h_position": record[_H],
        "cross_track_error": values[_E],
        "progress": values[_PROGRESS],
        "speed": values[_VT],
        "reference_speed": values[_VREF],
        "speed_error": values[_VT] - values[_VREF],
        "wheel_rates": record[_RATES],
        "command": record[_COMMAND],
        "wheel_angles": record[_ANGLES],
        "measured_pose": record[_MEASURED],
        "reward_terms": {
            "track": values[_TRACK],
            "speed": values[_SPEED],
            "heading": values[_HEADING],
            "smooth": values[_SMOOTH],
        },
        "time": time,
    }
    if path is not None:  # in key order by assignments: cheaper than a ** of a conditional dict (single_step_parts.py)
        info["path"] = path
    info["true_robot"] = true_robot
    info["delay"] = delay
    info["slip"] = record[_SLIP]
    info["end_of_path"] = end_of_path
    return info


class AmigoBotV1Env(JsonSpecMixin, gym.Env[ObsArray, NDArray[np.floating[Any]]]):
    r"""AmigoBot path tracking on the real robot: point H follows a path of any family, steered by wheel-rate setpoints.

    ## Description

    The kinematics of ``AmigoBot-v0`` (pose ``(x_A, y_A, beta)``, point H ``l3 = 0.08 m`` ahead of the axle
    midpoint A), with the robot as it is:

    * **Actuators.** Actions are wheel-rate *setpoints*; the firmware ramps the translational speed at 0.3 / 0.75
      m/s^2 (up / down) and the rotational speed at 0.87 / 2.5 rad/s^2 towards them, wheel rates limited to 15 rad/s
      (:mod:`amigo_gym.model.actuators`). The wheel rates are state; episodes start at rest.
    * **Exact integration.** The speeds are piecewise linear in time; the pose advances by the exact generalised
      Fresnel integral on each piece (:mod:`amigo_gym.model.fresnel`).
    * **The robot is not the model.** ``robot`` is the nominal robot (action scale, observation, policies);
      ``true_robot`` the simulated one; ``randomize`` draws wheel radii, track, slip, delay and measurement noise
      per episode (:mod:`amigo_gym.model.randomization`).
    * **Many paths.** ``path``: ``"circle"``, ``"manoeuvre"``, ``"figure8"``, ``"lane_change"``, ``"random"``,
      ``"mixed"`` or a path object of your own (:class:`amigo_gym.paths.PathSpec`); ``speed`` a constant or a
      range, ``speed_profile="trapezoid"`` for start–cruise–brake.
    * **Feasibility.** A task whose exact inverse solution (for a drawn family, a bound:
      :func:`amigo_gym.task.v1.drawn_feasibility_problem`) needs more wheel rate or rotational acceleration than
      the robot has is refused at construction (``feasibility="error"``, the default); ``"warn"`` and ``"off"`` run
      it. The report is ``env.feasibility`` and ``info["feasibility"]`` at reset.

    ## Action Space

    ``Box(-1, 1, (2,), float32)``: the setpoints of wheel 1 (right) and wheel 2 (left) over
    ``w_max = robot.max_wheel_rate`` of the *nominal* robot (15 rad/s). Clipped to [-1, 1]; NaN, infinities,
    wrong shapes raise ``ValueError``, non-numbers ``TypeError``.

    ## Observation Space

    ``Box(low, high, (18 + 3 (len(preview) - 3),), float32)``: the fields of :func:`amigo_gym.task.v1.obs_fields`
    (errors of H, path preview in the robot frame, reference speed now and 1 s ahead, speed error, measured
    wheel rates, previous command). The true robot, slip and delay are never observed.

    ## Rewards

    ``track * speed * heading * smooth``, each in [0, 1], from the true state (:mod:`amigo_gym.task.v1`);
    the terms are in ``info["reward_terms"]``.

    ## Starting State

    H at the path's start plus ``U(-1, 1) * init_position_noise`` per axis, heading along the path plus
    ``U(-1, 1) * init_heading_noise``, wheels at rest. ``reset(options={"pose": (x_A, y_A, beta)})`` sets
    the start pose.

    ## Episode End

    Terminated when H is farther than ``termination_distance`` from the path, or reaches the end of an
    open path: passes it, or comes within ``goal_tolerance`` [m] of the end point (when > 0); truncated by
    ``max_episode_steps`` (600 by default: 60 s at dt = 0.1 s). ``info["end_condition"]`` says which fired.

    ## Info

    ``pose`` (true A), ``h_position``, ``cross_track_error`` [m], ``progress`` (H's arc length) [m],
    ``speed`` (true speed of A) and ``reference_speed`` [m/s], ``speed_error`` [m/s], ``wheel_rates``
    (actual, end of step) and ``command`` (the setpoints) [rad/s], ``wheel_angles`` [rad], ``measured_pose``,
    ``reward_terms``, ``time`` [s], ``path`` (family and parameters), ``true_robot`` (``r1``, ``r2``, ``l1`` [m]),
    ``delay`` [s], ``slip`` (this step's loss of ground speed per wheel), ``end_of_path`` (H reached the end of an
    open path: the episode terminated as a success), ``end_condition`` (``""``, ``"goal"``, ``"end_of_path"`` or
    ``"off_path"``: :data:`amigo_gym.task.v1.END_CONDITIONS`); at reset, for a fixed path, ``feasibility``.

    ## Arguments

    Every field of :class:`amigo_gym.task.v1.TrackingParams` as a keyword (mappings accepted for ``robot``,
    ``true_robot``, ``actuators``, ``randomize``, ``path_params`` and ``params``), ``render_mode``, and ``kernel``:
    ``"auto"`` (default: the compiled step when numba is installed, unless ``AMIGO_GYM_KERNEL=numpy``), ``"numpy"``
    (the reference code of :mod:`amigo_gym.task.v1`) or ``"numba"``. The compiled step runs on the built-in path
    families and on AmigoBot-v0's circle and manoeuvre with ``observation="v0"``; a path object of your own runs the
    reference. Both agree to 1e-9; one seed on one route gives the same bits.

    Every argument is checked at construction, in one line naming the field, the value and the allowed range
    (``dt`` in [0.001, 1] s; unknown, out-of-range and unused ``path_params`` refused); conflicting settings are
    refused, not clipped (``actuators.delay`` plus the highest ``randomize.delay`` above 0.5 s; a trapezoid too
    short to reach its speed).

    ```python
    import gymnasium as gym
    import amigo_gym

    env = gym.make("AmigoBot-v1", path="mixed", speed=(0.1, 0.4), randomize="hard")
    ```

    ## Version History

    * v1: the real robot, path families and speed profiles, a generalising observation.
    * v0: the ideal robot on the paper's circle (``AmigoBot-v0``).
    """

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": 10.0}  # noqa: RUF012

    #: points of H kept for the rendered trail (the most recent ones)
    trail_length: int = 4096
    #: AmigoBot-v0's classes: the path without a feasibility report (check_v0 checked that it is drivable)
    _v0 = False

    def __init__(
        self, render_mode: str | None = None, *, params: Any = None, kernel: str = "auto", **settings: Any
    ) -> None:
        owner = type(self).__name__
        p = self.params = tracking.make_tracking_params(owner, params, **settings)
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(f"render_mode must be one of {list(RENDER_MODES)} or None, got {render_mode!r}")
        self.render_mode = render_mode
        self.metadata = {**type(self).metadata, "render_fps": 1.0 / p.dt}
        self.action_space, self.observation_space = box_spaces(tracking.obs_bounds(p))  # type: ignore[assignment]
        self._trail: deque[tuple[float, float]] = deque(maxlen=self.trail_length)
        self._renderer: Renderer | None = None
        self._needs_reset = True
        self._ended: bool | None = False  # None: terminated and warned
        self._k = tracking.constants(p)
        self._kernel = fast_v1.StepKernel(self._k) if fast_v1.use_kernel(owner, kernel) else None
        self._in_kernel = False  # this episode's state lives in the kernel's block
        self._steps = 0
        self._delay = 0.0
        #: the fixed path (None for drawn paths) and its feasibility report (None for drawn paths and AmigoBot-v0)
        self.path, self.feasibility = (p.path, None) if self._v0 else tracking.check_task(p)
        #: the AmigoBot-v0 task these settings are (:func:`amigo_gym.task.v1.v0_settings`), or None
        self.v0_params = tracking.v0_settings(p)
        self._castor = 0.0  # the castor's rolling angle [rad] (v0's info) on the reference route
        self._goal = (math.nan, math.nan)
        self._obs_shape: tuple[int, ...] = self.observation_space.shape  # type: ignore[assignment]
        self._ring = np.zeros((self._k.ring_length, 2)) if self._kernel is None else self._kernel.ring
        self._state: tracking.State | None = None
        self._episode: tracking.Episode | None = None
        self._path_info: dict[str, Any] = {}
        self._true_robot: dict[str, float] = {}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsArray, dict[str, Any]]:
        """Start an episode (class docstring, *Starting State*); ``options={"pose": (x_A, y_A, beta)}`` sets the start
        pose [m, m, rad]. ``ValueError`` on an unknown option key or a bad pose."""
        check_reset_options(options)
        pose = tuple(parse_pose_option(options["pose"]).tolist()) if options is not None and "pose" in options else None
        super().reset(seed=seed)
        k = self._k
        kern = self._kernel
        progress, loops, at = (None, None, None) if kern is None else (kern.progress, fast_v1.path_loops(), kern.pose)
        self.path, self._path_info, ep, st = tracking.start_episode(self.np_random, k, pose, progress, loops, at)
        self._episode = ep
        self._state = st
        # the command the robot was executing before the first step: its wheels' state (0 at rest)
        self._ring[:] = (st.a1 * k.w_max, st.a2 * k.w_max)
        self._ring_step = 0
        self._steps = int(st.steps)
        self._delay = int(ep.lag) * self.params.dt + float(ep.t_switch)
        self._true_robot = {"r1": float(ep.r1), "r2": float(ep.r2), "l1": float(ep.l1)}
        self._goal = tracking.goal_point(self._k.params, self.path)
        self._in_kernel = kern is not None and fast_v1.compiled_path(self.path, k.params)
        self._castor = 0.0
        if kern is not None and self._in_kernel:
            kern.load(self.path, st, ep, tracking.ep_l3_differs(k, ep))
            v_true, t = tracking.start_speed_time(st, ep)
            obs = np.empty(self._obs_shape, dtype=np.float32)
            kern.evaluate(kern.consts, kern.path, kern.ws, 0, obs, kern.record, v_true, t)
            kern.fill()
            rec = kern.record.copy()
            rec[_L.R_COMMAND] = self._ring[0]  # a start: the command the robot was executing, no slip
            rec[_L.R_SLIP] = 0.0
            info = self._record_info(rec, kern.scalars.tolist())
        else:
            out = tracking.reset_columns(k, self.path, st, ep, tracking.NO_NOISE)
            obs = np.array(out.obs, dtype=np.float32)
            info = self._info(out, tracking.NO_NOISE)
        if self.v0_params is None:
            info["end_condition"] = ""
            if self.feasibility is not None:
                info["feasibility"] = copy.deepcopy(self.feasibility)  # new objects at every reset
        self._needs_reset = False
        self._ended = False
        self._trail.clear()
        self._trail.append(tuple(info["h_position"].tolist()))
        if self.render_mode == "human":
            self.render()
        return obs, info

    def step(self, action: NDArray[np.floating[Any]]) -> tuple[ObsArray, SupportsFloat, bool, bool, dict[str, Any]]:
        """Hold the wheel-rate commands ``clip(action, -1, 1) * w_max`` for ``dt`` and report the new state.

        Raises ``ResetNeeded`` before the first ``reset()``, ``TypeError`` for an action that is not real numbers,
        ``ValueError`` for a wrong shape or NaN/inf entries. Stepping a terminated episode warns once per episode and
        goes on integrating; truncation belongs to the ``TimeLimit`` wrapper of ``gym.make``.
        """
        if self._needs_reset:
            raise gym.error.ResetNeeded(f"{type(self).__name__}: call reset() before step()")
        a1, a2 = task.action_pair(action)
        if self._ended:
            gym.logger.warn(
                f"{type(self).__name__}: step() called after the episode was terminated (the environment has already "
                "returned terminated = True); call reset() to start a new one (the steps go on integrating, outside "
                "the task)"
            )
            self._ended = None  # warned: once per episode
        obs, reward, terminated, info = self._advance(a1, a2)
        if self.render_mode is not None:
            self._trail.append(tuple(info["h_position"].tolist()))
            if self.render_mode == "human":
                self.render()
        if terminated and self._ended is False:
            self._ended = True
        return obs, reward, terminated, False, info

    def _advance(self, a1: float, a2: float) -> tuple[ObsArray, float, bool, dict[str, Any]]:
        self._ring_step += 1
        if self._in_kernel:
            return self._step_kernel(a1, a2)
        assert self._state is not None and self._episode is not None
        st, out, noise = tracking.step_columns(
            self._k, self.path, self._state, self._episode, self._ring, self._ring_step, a1, a2
        )
        self._state = st
        self._steps = int(st.steps)
        if self.v0_params is not None:
            robot = self._k.nominal
            v, bdot = body_velocity_of(float(st.w1), float(st.w2), robot.r1, robot.r2, 2.0 * robot.l1)
            self._castor = advance_angle(self._castor, castor_rate_float(v, bdot, robot.l5, robot.r3), self.params.dt)
        info = self._info(out, noise)
        return np.array(out.obs, dtype=np.float32), float(out.reward), self._end(bool(out.terminated), info), info

    def _step_kernel(self, a1: float, a2: float) -> tuple[ObsArray, float, bool, dict[str, Any]]:
        kern = self._kernel
        assert kern is not None
        kern.run_record(self._ring_step, a1, a2, *kern.args)
        self._steps += 1
        v = kern.scalars.tolist()
        info = self._record_info(kern.record.copy(), v)
        return kern.obs.copy(), v[_REWARD], self._end(v[_TERM] != 0.0, info), info

    def _end(self, terminated: bool, info: dict[str, Any]) -> bool:
        # with the goal of an open path (goal_tolerance), which sets end_of_path; and info["end_condition"] (not v0's)
        if self.v0_params is not None:
            return terminated
        gx, gy = self._goal  # NaN: no goal
        h = info["h_position"]
        if gx == gx and tracking.goal_reached(self._k.params, float(h[0]), float(h[1]), gx, gy):
            info["end_of_path"] = True
            info["end_condition"] = "goal"
            return True
        info["end_condition"] = "end_of_path" if info["end_of_path"] else "off_path" if terminated else ""
        return terminated

    def _record_info(self, rec: Array, v: list[float]) -> dict[str, Any]:
        time = self._steps * self.params.dt
        if self.v0_params is not None:
            return v0_record_info(rec, v, time)
        return record_info(rec, v, time, self._true_robot.copy(), self._delay, v[_END] != 0.0, self._path_info.copy())

    def _current_state(self) -> tracking.State:
        """The state of the episode (:class:`amigo_gym.task.v1.State` of floats); ``ResetNeeded`` before a reset."""
        if self._state is None:
            raise gym.error.ResetNeeded("call reset() before _current_state() on AmigoBot-v1")
        if self._kernel is not None and self._in_kernel:
            return self._kernel.state(self._steps)
        return self._state

    def _info(self, out: tracking.Outcome, noise: StepNoise) -> dict[str, Any]:
        assert self._state is not None
        rec = reference_record(self._k.w_max, self._state, out, noise, self._castor)
        return self._record_info(rec, rec[_L.R_ERROR :].tolist())

    def _render_state(self) -> dict[str, Any]:
        st = self._current_state()
        return {
            "pose": np.array((st.x, st.y, st.beta)),
            "wheel_angles": np.array((st.alpha1, st.alpha2)),
            "time": float(int(st.steps) * self.params.dt),
        }

    def render(self) -> NDArray[np.uint8] | None:
        """The ``(H, W, 3)`` uint8 frame for ``render_mode="rgb_array"`` (:mod:`amigo_gym.envs.rendering`); ``None``
        otherwise."""
        if self.render_mode is None:
            gym.logger.warn(
                "render() called without a render_mode; pass render_mode='rgb_array' or 'human' to gym.make"
            )
            return None
        if self._needs_reset:
            raise gym.error.ResetNeeded(f"{type(self).__name__}: call reset() before render()")
        if self._renderer is None or self._renderer.path is not self.path:
            self.close()
            self._renderer = Renderer(self.params, self.path, self.render_mode)
        return self._renderer.draw(trail=self._trail, **self._render_state())

    def close(self) -> None:
        """Close the render window, if any."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __getstate__(self) -> dict[str, Any]:
        """Pickle and deep-copy without the renderer (recreated when next used)."""
        state = self.__dict__.copy()
        state["_renderer"] = None
        return state
