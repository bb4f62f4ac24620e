"""Design kernels: swarm unions over candidate masks, the ring-gap bound."""
