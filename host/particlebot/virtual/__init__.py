"""Virtual particles: the real firmware logic in a simulated light field, on simulated air."""
