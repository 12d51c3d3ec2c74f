"""The .mission language: a sequence of navigation goals in a room (thesis 4.3.1)."""
