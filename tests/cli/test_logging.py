"""The package logs, it does not print: its logger has a NullHandler, and the form
compiler's chatter (distutils' INFO records on the root logger while dolfinx's JIT compiles)
is dropped unless the package logger is enabled for DEBUG (``--debug``).  The end-to-end
check, a script compiling its forms afresh with nothing on stderr, is in
test_fenicsx_demo.py."""
from __future__ import annotations

import logging

import dolfinx_friction

DISTUTILS = "/usr/lib/python3/dist-packages/setuptools/_distutils/spawn.py"


def _record(level: int, pathname: str) -> logging.LogRecord:
    return logging.LogRecord("root", level, pathname, 1, "x86_64-linux-gnu-gcc -c form.c",
                             None, None)


def test_compiler_chatter_is_dropped_unless_debug():
    root, package = logging.getLogger(), logging.getLogger(dolfinx_friction.__name__)
    assert any(isinstance(h, logging.NullHandler) for h in package.handlers)
    assert not root.filter(_record(logging.INFO, DISTUTILS))
    assert root.filter(_record(logging.WARNING, DISTUTILS))  # warnings and errors pass
    assert root.filter(_record(logging.INFO, "/home/user/script.py"))  # the user's own records
    level = package.level
    package.setLevel(logging.DEBUG)
    try:
        assert root.filter(_record(logging.INFO, DISTUTILS))
    finally:
        package.setLevel(level)
