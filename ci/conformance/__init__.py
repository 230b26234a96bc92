"""Conformance: the registered properties, their lying engines, the sources of scenarios, campaigns and reproducers."""
