"""The top layer: the overtake CLI, campaigns (conformance, simulation, audit), executors, records, benchmarks."""
