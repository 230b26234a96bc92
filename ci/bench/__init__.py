"""Benchmarks: each module times one thing, prints a table with the machine and the
date (``python -m ci.bench.NAME``)."""
