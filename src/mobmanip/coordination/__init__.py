"""Teams that move: several mobile manipulators carrying one object along a path."""
