"""Model-to-text: the concrete model (coordinates, catalogue mapping) and one generator per target."""
