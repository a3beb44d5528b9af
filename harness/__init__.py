"""srr: a record-and-replay regression harness for robot software tested in simulation."""

__version__ = "0.1.0"
__all__ = ["__version__"]
