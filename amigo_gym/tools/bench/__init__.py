"""Benchmarks of the exact step and of the environments against peers measured in the same run."""
