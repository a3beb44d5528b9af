"""The smallest valid scenario file, the base the scenario tests edit into bad ones."""

GOOD = """\
format_version: 1
name: t
duration: 2
robots:
  - name: forklift
    model: forklift
"""
