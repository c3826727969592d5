"""The sources' published results set beside ours (DACS, Decima, Oxide).

Each source has a module here with ``STUDY`` (the bundled study whose run measures ours) and
``claims(rows, conditions) -> list[Claim]``; the report collects them into one table."""
