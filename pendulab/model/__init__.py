"""Physics: parameters, the Lagrange builder, the rigid and elastic models, simulation."""
