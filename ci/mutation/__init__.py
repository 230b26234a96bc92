"""The mutation check: single-rule faults the project's own checks must catch, and the runner that applies them."""
