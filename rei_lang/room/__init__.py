"""The .room language: typed model, linker (names → objects), layout (floors → cells), checks."""
