"""``overtake report``: the output folders of crossval, simulate and audit as one page a person reads."""
