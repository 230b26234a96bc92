"""The PyBullet simulator (see issue: simulator)."""
