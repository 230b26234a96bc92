"""The PyBullet simulator, assembled from parts: a closed loop that checks plans against physics."""
