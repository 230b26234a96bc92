"""The top layer, a room per job: the CLI (``cli``), the campaigns (``conformance``, ``simulation``, ``audit``,
``mutation``), the benchmarks (``bench``), the report (``report``) and what they share (``shared``)."""
