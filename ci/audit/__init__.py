"""The audit of the grid abstraction: closed-loop drives against traffic and sensing that do not keep to it."""
