"""The compiled step: numba kernels that run the task's step for one robot or a batch, bit for bit as the
Python float reference in :mod:`amigo_gym.task` (``kernel="numpy"``).

``fast`` / ``_kernels`` are AmigoBot-v0's; ``fast_v1`` / ``_kernels_v1`` / ``fast_v1_batch`` AmigoBot-v1's.
numba is a core dependency where it ships wheels (the ``fast`` extra elsewhere): without it every env runs the
reference.
"""
