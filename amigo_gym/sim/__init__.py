"""The compiled step (numba) of :mod:`amigo_gym.task.v1`'s step for one robot (:mod:`amigo_gym.sim.fast_v1`) or a
batch (:mod:`amigo_gym.sim.fast_v1_batch`); without numba every env runs the reference."""
