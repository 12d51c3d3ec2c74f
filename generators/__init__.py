"""Model-to-text: the concrete model (coordinates, catalogue mapping), one generator per target."""
