"""The robot model: what the AmigoBot is and how it moves, independent of any task.

==================  ==========================================================================================
module              holds
==================  ==========================================================================================
``params``          :class:`RobotParams` (geometry [m]) and :class:`EnvParams` (settings), validated
``kinematics``      the exact differential-drive step derived from the D–H constraints (closed forms)
``fresnel``         Fresnel-type integrals of the pose over a linear ramp of the wheel rates
``actuators``       the firmware's wheel-rate ramps, delays and the exact pose over them
``randomization``   the true robot drawn around the nominal one, slip and measurement noise
==================  ==========================================================================================
"""
