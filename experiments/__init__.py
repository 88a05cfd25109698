"""Experiment scripts behind the ``amigo-gym`` command (each file readable on its own)."""
