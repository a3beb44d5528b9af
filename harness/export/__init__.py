"""Run directories written out for other tools' viewers (``srr export``): :mod:`.rerun`."""
