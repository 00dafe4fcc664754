"""Simulated machines of the identification benchmarks, made independently of the harness."""
