"""`python -m rei.runtime.commands ...` is `rei ...` (the form child processes and tests use)."""

from rei.runtime.commands.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
