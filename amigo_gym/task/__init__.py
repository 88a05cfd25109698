"""The tasks: where H must go, what the agent sees and what it is rewarded for, as pure batched functions.

``v0``       AmigoBot-v0's task: the ideal robot on the paper's circle (or manoeuvre), its observation and reward
``v1``       AmigoBot-v1's task: the real robot on any path (:mod:`amigo_gym.paths`), actuators, noise, delays
``inverse``  the analytic inverse solution: the wheel angles and rates that drive H along a circle or manoeuvre

Both import :mod:`amigo_gym.model` and :mod:`amigo_gym.paths`; the envs, policies and the compiled step
(:mod:`amigo_gym.sim`) import them.
"""
