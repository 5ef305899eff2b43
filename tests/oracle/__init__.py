"""Test oracle: the original numpy implementation of the assembly (forward kinematics,
B/M/N twists, Phi and its Jacobian) and of the layout retraction, kept only to check the
compiled engine against an independent formulation. Not part of the library."""
