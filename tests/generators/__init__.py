"""Tests of the generators: concrete model, targets, `rei-gen generate` and `rei-gen show`."""
