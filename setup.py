"""Builds the C stroke kernel (softclose/simulation/kernel/_kernel.c) as an extension; metadata is in pyproject.toml.

The extension carries the tag of the source it was compiled from (BLAKE2b of ``_kernel.c`` and
``_layout.h``, as :func:`softclose.simulation.kernel.library.source_tag` computes it), so the
package knows its kernel is current by content, never by file times."""
from hashlib import blake2b
from pathlib import Path

from setuptools import Extension, setup

KERNEL = Path("softclose/simulation/kernel")
TAG = blake2b((KERNEL / "_kernel.c").read_bytes() + (KERNEL / "_layout.h").read_bytes(),
              digest_size=8).hexdigest()

setup(ext_modules=[Extension("softclose.simulation.kernel._kernel", ["softclose/simulation/kernel/_kernel.c"],
                             depends=["softclose/simulation/kernel/_layout.h"],
                             define_macros=[("SC_SOURCE_TAG", f'"{TAG}"')],
                             extra_compile_args=["-O3"])])
