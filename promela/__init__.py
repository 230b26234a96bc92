"""The Spin engine: Promela rendered from spec/, verifiers compiled once and cached."""
