"""The platform: child processes that never outlive REI (``processes``), scratch folders that
name their owner (``scratch``), and forking a warm child instead of executing a fresh
interpreter (``warm``, ``fork``).

It may import only the standard library: every wing above uses it. It must never know what a
run, a controller or a campaign is.
"""
