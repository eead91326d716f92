"""Benchmarks are run by `make bench` (pytest benches --benchmark-only); the normal test run
does not collect this folder."""
