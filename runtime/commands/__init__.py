"""`rei` sub-commands: each module here defines ``register(subparsers)``; ``cli`` is `rei`
itself (``python -m rei.runtime.commands``).

Argparse and printing only: each command checks its options and calls the public functions
of the wings below (runs, campaigns, presentation, observation, bus). Nothing below imports
this package.
"""
