"""Templates of the `rx` target: the generated event-automata module (data only)."""
