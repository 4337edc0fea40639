"""Shared code for radia's validation tools (compare.py, benchmark.py)."""
