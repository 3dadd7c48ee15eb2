"""Marks for tests that need one of the package's optional extras: without it they skip, with
the install line as the reason, so the README's `make test` (default extras) passes on a fresh
clone while CI also runs them with every extra."""

import pytest

from cpg_actor.robots.common import mjx_runtime

MJX = pytest.mark.skipif(not mjx_runtime.available(), reason='needs pip install -e ".[mjx]"')


def _warp_installed() -> bool:
    try:
        mjx_runtime.check_impl("warp")
    except mjx_runtime.MjxUnavailable:
        return False
    return True


WARP = pytest.mark.skipif(
    not (mjx_runtime.available() and _warp_installed()), reason='needs pip install -e ".[warp]"'
)
