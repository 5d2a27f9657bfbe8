"""Benchmarks and stress tests of simgrip (physics modules never import this package)."""
