"""The Python engines: the reference interpreter and its planners, the offset abstraction, and the Z3 encoding."""
