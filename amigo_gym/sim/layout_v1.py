"""The layouts of the vectors of the compiled step (:mod:`amigo_gym.sim._kernels_v1`) and their index constants.

Never imports numba.
"""

from __future__ import annotations

from amigo_gym.model import actuators

#: scalar entries at the head of ``consts`` (the variable-length parts follow: :mod:`amigo_gym.sim._kernels_v1`)
CONSTANT_FIELDS: tuple[str, ...] = (
    "dt", "w_max", "r1", "r2", "l1", "two_l1",  # [s], [rad/s], the nominal wheel radii, half track, 2 l1 [m]
    "accel", "decel", "rot_accel", "rot_decel",  # firmware ramps [m/s^2], [rad/s^2]
    "l3", "error_scale", "e_max", "termination_distance", "preview_scale", "v_max",  # [m], [m], [-], [m], [m], [m/s]
    "sigma_track", "sigma_speed", "smooth_scale_sq",  # the reward's scales [m], [m/s], [-]
    "trapezoid", "profile_accel", "profile_decel",  # 1.0 for speed_profile="trapezoid" else 0.0; [m/s^2]
    "window", "speed_lookahead", "n_preview", "n_nodes",  # [m], [s], counts (actuator nodes per piece: 10 n_sub)
    "position_noise", "heading_noise", "wheel_rate_noise",  # noise standard deviations [m], [rad], [rad/s]
    "ideal", "obs_v0", "reward_v0",  # 1.0 for ideal_actuators, observation="v0", reward="v0", else 0.0
    "l5", "r3",  # nominal castor swivel distance and castor radius [m]
    "path_kind",  # PATH_CLOTHOID (the path vector), PATH_CIRCLE or PATH_MANOEUVRE (closed forms below)
    # the circle's centre [m], unit start radius, direction (+1 left), radius [m]; the manoeuvre's straight part [m]
    "cx", "cy", "r0x", "r0y", "direction", "radius", "straight_length",
)  # fmt: skip
_C = {name: i for i, name in enumerate(CONSTANT_FIELDS)}
C_DT, C_W_MAX, C_R1, C_R2, C_L1, C_TWO_L1 = (_C[n] for n in CONSTANT_FIELDS[0:6])
C_ACC, C_DEC, C_RACC, C_RDEC, C_L3, C_ERROR_SCALE = (_C[n] for n in CONSTANT_FIELDS[6:12])
C_E_MAX, C_TERM, C_PREVIEW_SCALE, C_V_MAX, C_SIG_T, C_SIG_V = (_C[n] for n in CONSTANT_FIELDS[12:18])
C_SMOOTH_SQ, C_TRAPEZOID, C_PACC, C_PDEC, C_WINDOW = (_C[n] for n in CONSTANT_FIELDS[18:23])
C_LOOKAHEAD, C_N_PREVIEW, C_N_NODES = (_C[n] for n in CONSTANT_FIELDS[23:26])
C_POS_NOISE, C_HEAD_NOISE, C_RATE_NOISE = (_C[n] for n in CONSTANT_FIELDS[26:29])
C_IDEAL, C_OBS_V0, C_REWARD_V0, C_L5, C_R3, C_PATH_KIND = (_C[n] for n in CONSTANT_FIELDS[29:35])
C_CX, C_CY, C_R0X, C_R0Y, C_DIRECTION, C_RADIUS, C_STRAIGHT = (_C[n] for n in CONSTANT_FIELDS[35:42])
#: values of ``consts[C_PATH_KIND]``: a :class:`~amigo_gym.paths.ClothoidPath` (its flat vector), a
#: :class:`~amigo_gym.paths.CirclePath` or a :class:`~amigo_gym.paths.ManoeuvrePath` (closed forms of the constants)
PATH_CLOTHOID, PATH_CIRCLE, PATH_MANOEUVRE = 0.0, 1.0, 2.0
#: where the variable-length parts of ``consts`` start
C_TAIL = len(CONSTANT_FIELDS)
#: Gauss–Legendre nodes of the path quadrature (:data:`amigo_gym.model.fresnel.NODES`)
PATH_NODES = 10

#: entries of ``ws``: the state (:class:`amigo_gym.task.v1.State`), the episode (:class:`amigo_gym.task.v1.Episode`;
#: ``l3_differs`` 1.0 when the true l3 is not the nominal one), the outputs of a step or an evaluation
WS_FIELDS: tuple[str, ...] = (
    # state, updated by step; "castor": the castor wheel's rolling angle [rad] (ideal steps: AmigoBot-v0's info)
    "x", "y", "beta", "w1", "w2", "alpha1", "alpha2", "progress", "a1", "a2", "steps", "castor",
    # episode, read only
    "r1", "r2", "l1", "l3", "lag", "t_switch", "v_cruise", "t_brake", "l3_differs",
    # outputs: "heading" the heading reward term, "arg_*" the arguments of the track, speed and smoothness
    # exponentials, "terminated" and "end_of_path" 1.0 / 0.0, "command*" the setpoints written this step [rad/s]
    "h_x", "h_y", "error", "v_true", "v_ref", "meas_x", "meas_y", "meas_beta", "meas_w1", "meas_w2",
    "heading", "arg_track", "arg_speed", "arg_smooth", "terminated", "end_of_path", "command1", "command2",
    # the per-step draws: the episode's slip bound, whether anything is drawn (1.0 / 0.0), this step's draws
    "slip_max", "noise_on", "slip1", "slip2", "noise_x", "noise_y", "noise_beta", "noise_rate1", "noise_rate2",
)  # fmt: skip
_W = {name: i for i, name in enumerate(WS_FIELDS)}
W_X, W_Y, W_BETA, W_W1, W_W2, W_AL1, W_AL2, W_PROGRESS, W_A1, W_A2, W_STEPS = (_W[n] for n in WS_FIELDS[0:11])
W_CASTOR = _W["castor"]
W_R1, W_R2, W_L1, W_L3, W_LAG, W_TS, W_VC, W_TB, W_L3D = (_W[n] for n in WS_FIELDS[12:21])
W_HX, W_HY, W_E, W_VT, W_VREF, W_MX, W_MY, W_MB, W_MW1, W_MW2 = (_W[n] for n in WS_FIELDS[21:31])
W_HEADING, W_ARG_T, W_ARG_V, W_ARG_S, W_TERM, W_END, W_CMD1, W_CMD2 = (_W[n] for n in WS_FIELDS[31:39])
W_SLIP_MAX, W_NOISE_ON, W_SLIP1, W_SLIP2 = (_W[n] for n in WS_FIELDS[39:43])
W_NX, W_NY, W_NB, W_NR1, W_NR2 = (_W[n] for n in WS_FIELDS[43:48])
#: the info record (:func:`amigo_gym.sim._kernels_v1.fill_record`): the workspace entries of the info's seven arrays,
#: then of its scalars, then the exponentials of the track, speed and smoothness arguments, the smoothness term and
#: the reward
RECORD_ROWS = ("x", "y", "beta", "h_x", "h_y", "w1", "w2", "command1", "command2", "alpha1", "alpha2", "meas_x",
               "meas_y", "meas_beta", "slip1", "slip2")  # fmt: skip
RECORD_SCALARS = ("error", "progress", "v_true", "v_ref", "heading", "end_of_path", "terminated", "castor")
R_ERROR = len(RECORD_ROWS)
R_HEADING = R_ERROR + RECORD_SCALARS.index("heading")
R_TRACK = R_ERROR + len(RECORD_SCALARS)
R_SPEED, R_SMOOTH_EXP, R_SMOOTH, R_REWARD = R_TRACK + 1, R_TRACK + 2, R_TRACK + 3, R_TRACK + 4
RECORD_WIDTH = R_REWARD + 1
#: the record's slices of the info's seven arrays (:data:`RECORD_ROWS`), in their order; the index of each scalar
R_POSE, R_H, R_RATES, R_COMMAND, R_ANGLES, R_MEASURED, R_SLIP = (
    slice(RECORD_ROWS.index(a), RECORD_ROWS.index(b) + 1)
    for a, b in (("x", "beta"), ("h_x", "h_y"), ("w1", "w2"), ("command1", "command2"), ("alpha1", "alpha2"),
                 ("meas_x", "meas_beta"), ("slip1", "slip2"))
)  # fmt: skip
R_HX, R_HY = RECORD_ROWS.index("h_x"), RECORD_ROWS.index("h_y")
R_PROGRESS, R_VT, R_VREF, R_END, R_TERM, R_CASTOR = (
    R_ERROR + RECORD_SCALARS.index(n) for n in ("progress", "v_true", "v_ref", "end_of_path", "terminated", "castor")
)
#: :data:`RECORD_ROWS` and :data:`RECORD_SCALARS` as workspace indices
RECORD_WS = tuple(WS_FIELDS.index(name) for name in (*RECORD_ROWS, *RECORD_SCALARS))

#: scratch entries after :data:`WS_FIELDS`: the actuator step's (:data:`amigo_gym.model.actuators.SCRATCH`, from
#: ``S_ACT``), then the normal draws' uniforms ``u1`` and angles ``2 pi u2`` (5 each)
WS_SCRATCH = actuators.SCRATCH + 2 * 5
S_ACT = len(WS_FIELDS)
S_U1 = S_ACT + actuators.SCRATCH
S_U2 = S_U1 + 5
