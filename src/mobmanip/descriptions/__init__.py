"""Robot files at the edge: where they live and how a URDF is read and checked."""
