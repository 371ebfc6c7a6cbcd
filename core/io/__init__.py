"""The files: the design file, the measured data, the tolerances and targets, and the exports
(docs/files.md, docs/export.md)."""
