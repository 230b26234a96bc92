"""Reference engines: the Python interpreter and planners, and (later) the Z3 encoding."""
