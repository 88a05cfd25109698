"""The compiled step of AmigoBot-v0 and AmigoBot-v1: numba kernels that run :mod:`amigo_gym.task.v1`'s step for one
robot (:mod:`amigo_gym.sim.fast_v1`) or a batch (:mod:`amigo_gym.sim.fast_v1_batch`), the scalar functions of the
reference compiled (:mod:`amigo_gym.sim._kernels_v1`), agreeing with the reference (``kernel="numpy"``) to 1e-9.

numba is a core dependency where it ships wheels (the ``fast`` extra elsewhere): without it every env runs the
reference.
"""
