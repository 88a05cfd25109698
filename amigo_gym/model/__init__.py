"""The robot model, independent of any task: ``params`` (validated settings), ``kinematics`` (the exact
differential-drive step), ``fresnel`` (the pose over linear ramps), ``actuators`` (the firmware's ramps and delay),
``randomization`` (the true robot, slip and noise drawn)."""
