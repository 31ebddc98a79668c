"""Benchmarks and model-selection studies: work-precision, stability, model hierarchy."""
