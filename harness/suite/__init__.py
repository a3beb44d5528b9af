"""``srr suite``: many scenario runs, their statistics, and the outputs CI reads."""

__all__: list[str] = []
