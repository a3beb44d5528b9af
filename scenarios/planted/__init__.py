"""Plug-ins with defects planted on purpose, to show that ``srr search`` finds them."""
