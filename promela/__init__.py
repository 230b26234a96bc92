"""Promela templates rendered from spec/ and the Spin engine (see issue: Spin engine)."""
