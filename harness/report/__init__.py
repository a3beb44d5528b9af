"""Outputs for people and CI systems: JUnit XML (and, later, the HTML report)."""
