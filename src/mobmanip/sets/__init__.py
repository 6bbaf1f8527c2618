"""Task-space sets with no robot inside: the TaskSet interface, ellipsoids, polytopes, zonotopes,
planar hulls and the linear programs that query them; and the paper's capacity sets built from
arrays (J_u, W, P, Q, xi, M_o, g_o and the limits)."""
