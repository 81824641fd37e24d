"""Benchmarks and stress cases of the simulator: work-precision, stress, baselines."""
