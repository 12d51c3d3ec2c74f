"""Golden files of every target on every example, and the code that regenerates them."""
