"""What the top layer's jobs share: records, executors, progress, option types, signals, scenario generation."""
