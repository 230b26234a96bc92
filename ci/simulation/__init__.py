"""The simulation campaign: seeded closed-loop drives, resumable, and the calibration of fault rates."""
