"""The robot: its spec, its Pinocchio model with the platform's constraint layer, task spaces,
platform detection, self-collision and configurations read from files."""
