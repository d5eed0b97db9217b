"""What every layer uses: the jit wrapper, argument checks, warnings at the user's line, per-rig caches."""
