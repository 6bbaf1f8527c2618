"""Arm postures: named ones from the spec, the paper's planar closed form, and inverse kinematics
that holds an object at a sweep's grid points."""
