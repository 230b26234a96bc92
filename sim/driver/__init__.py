"""What the AV decides, apart from the world it drives in: pure rules over what it sensed and its own state, no
physics engine, no bodies. The simulator feeds them readings and the car's pose and executes what they return."""
