"""The flyby simulation: sizing, swarm geometry, targeting and the flight of a swarm."""
