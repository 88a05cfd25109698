"""The robot model: what the AmigoBot is and how it moves, independent of any task.

==================  ==========================================================================================
module              holds
==================  ==========================================================================================
``params``          :class:`RobotParams` (geometry [m]) and :class:`EnvParams` (settings), validated
``kinematics``      the exact differential-drive step derived from the D–H constraints (closed forms)
``fresnel``         Fresnel-type integrals of the pose over a linear ramp of the wheel rates
``actuators``       the firmware's wheel-rate ramps, delays and the exact pose over them
``randomization``   the true robot drawn around the nominal one, slip and measurement noise
``inverse``         the analytic inverse solution: wheel angles and rates that drive H along a path
``symbolic``        the symbolic D–H derivation (sympy, imported only when used)
==================  ==========================================================================================

Imports only numpy (and sympy inside ``symbolic``) and these modules, in the order of the table's layers:
``params`` < ``kinematics`` < ``fresnel`` < ``actuators``, ``randomization``, ``inverse``, ``symbolic``.
"""
