"""Builds the C stroke kernel (softclose/simulation/kernel/_kernel.c) as an extension; metadata is in pyproject.toml."""
from setuptools import Extension, setup

setup(ext_modules=[Extension("softclose.simulation.kernel._kernel", ["softclose/simulation/kernel/_kernel.c"],
                             depends=["softclose/simulation/kernel/_layout.h"],
                             extra_compile_args=["-O3"])])
