"""Scripts shared by CI and people: benchmarks, campaigns, scenario generators."""
