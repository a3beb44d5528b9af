"""Systems under test: the plug-in contract and the bundled reference systems.

A plug-in subclasses :class:`SystemUnderTest` and is named in a scenario as ``"module:Class"``;
see :mod:`harness.sut.base` for the hooks and :class:`SutContext` for what it may touch."""

from harness.sut.base import SutContext, SystemUnderTest, load_sut, load_suts, sut_params

__all__ = ["SutContext", "SystemUnderTest", "load_sut", "load_suts", "sut_params"]
