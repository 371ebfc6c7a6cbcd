"""The ``bushing`` command line: an interface beside the app, over the core (docs/files.md)."""
