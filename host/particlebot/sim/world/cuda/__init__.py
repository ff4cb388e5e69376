"""The world on a GPU (numba-cuda): the CPU model's passes as CUDA kernels, and ensembles.

Placeholder description; see the module docstrings of laws, kernels and swarms.
"""
