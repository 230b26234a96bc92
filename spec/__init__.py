"""The single source of truth of the overtaking transition system.

Every engine (the Python interpreter, the Promela renderer, the Z3 encoder, the
simulator) reads its constants and rules from here and never re-declares them.
"""
