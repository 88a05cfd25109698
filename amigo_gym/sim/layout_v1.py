"""The layouts of the vectors of the compiled step (:mod:`amigo_gym.sim._kernels_v1`) and their index constants.

Never imports numba.
"""

from __future__ import annotations

from collections import namedtuple

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
C_DT, C_W_MAX, C_R1, C_R2, C_L1, C_TWO_L1 = range(0, 6)
C_ACC, C_DEC, C_RACC, C_RDEC, C_L3, C_ERROR_SCALE = range(6, 12)
C_E_MAX, C_TERM, C_PREVIEW_SCALE, C_V_MAX, C_SIG_T, C_SIG_V = range(12, 18)
C_SMOOTH_SQ, C_TRAPEZOID, C_PACC, C_PDEC, C_WINDOW = range(18, 23)
C_LOOKAHEAD, C_N_PREVIEW, C_N_NODES = range(23, 26)
C_POS_NOISE, C_HEAD_NOISE, C_RATE_NOISE = range(26, 29)
C_IDEAL, C_OBS_V0, C_REWARD_V0, C_L5, C_R3, C_PATH_KIND = range(29, 35)
C_CX, C_CY, C_R0X, C_R0Y, C_DIRECTION, C_RADIUS, C_STRAIGHT = range(35, 42)
#: values of ``consts[C_PATH_KIND]``: a :class:`~amigo_gym.paths.ClothoidPath` (its flat vector), a
#: :class:`~amigo_gym.paths.CirclePath` or a :class:`~amigo_gym.paths.ManoeuvrePath` (closed forms of the constants)
PATH_CLOTHOID, PATH_CIRCLE, PATH_MANOEUVRE = 0.0, 1.0, 2.0
#: where the variable-length parts of ``consts`` start
C_TAIL = len(CONSTANT_FIELDS)
#: Gauss–Legendre nodes of the path quadrature (:data:`amigo_gym.model.fresnel.NODES`)
PATH_NODES = 10

#: the compiled step's per-robot values, each a row ``(N,)`` of the float64 block ``ws (len(Rows._fields), N)``: the
#: state, updated by each step (:class:`amigo_gym.task.v1.State`'s fields, ``steps`` a float, then ``castor`` the
#: castor wheel's rolling angle [rad]), and the episode, read only (:class:`amigo_gym.task.v1.Episode`'s fields but
#: ``key``; ``l3_differs`` 1.0 when the true l3 is not the nominal one, else 0.0)
Rows = namedtuple(
    "Rows",
    "x y beta w1 w2 alpha1 alpha2 progress a1 a2 steps castor "
    "r1 r2 l1 l3 lag t_switch v_cruise t_brake slip_max l3_differs",
)
#: the info record of a step, a row of ``rec`` (``R_*`` its entries): the entries of the info's seven arrays (pose,
#: H, wheel rates, commands, wheel angles, measured pose [m, rad, rad/s], slips [-]), its scalars (cross-track error,
#: progress [m], true and reference speeds of A [m/s], heading term, end_of_path and terminated 1.0 / 0.0, castor
#: angle [rad]), the exponentials of the track, speed and smoothness arguments (the arguments until
#: :func:`amigo_gym.sim._kernels_v1.fill_record`), the smoothness term and the reward
RECORD_WIDTH = 29
(R_X, R_Y, R_BETA, R_HX, R_HY, R_W1, R_W2, R_CMD1, R_CMD2, R_AL1, R_AL2, R_MX, R_MY, R_MB, R_SLIP1, R_SLIP2,
 R_ERROR, R_PROGRESS, R_VT, R_VREF, R_HEADING, R_END, R_TERM, R_CASTOR,
 R_TRACK, R_SPEED, R_SMOOTH_EXP, R_SMOOTH, R_REWARD) = range(RECORD_WIDTH)  # fmt: skip
#: the record's slices of the info's seven arrays, in their order
R_POSE, R_H, R_RATES, R_COMMAND, R_ANGLES, R_MEASURED, R_SLIP = (
    slice(a, b + 1) for a, b in ((R_X, R_BETA), (R_HX, R_HY), (R_W1, R_W2), (R_CMD1, R_CMD2), (R_AL1, R_AL2),
                                 (R_MX, R_MB), (R_SLIP1, R_SLIP2))
)  # fmt: skip
