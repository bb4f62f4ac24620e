"""Models of the small body: shape (polyhedron or analytic), parameters, gravity field, data path."""
