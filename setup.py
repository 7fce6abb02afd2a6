"""Builds the C stroke kernel (softclose/_kernel.c) as an extension; metadata is in pyproject.toml."""
from setuptools import Extension, setup

setup(ext_modules=[Extension("softclose._kernel", ["softclose/_kernel.c"],
                             extra_compile_args=["-O3"])])
