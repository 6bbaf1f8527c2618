"""The paper's terms at a configuration: reduced dynamics (J_u, P, Q, xi) and the grasp (W, M_o, g_o)."""
