"""Starting worker processes safely from a process that runs JAX.

Workers are spawned (never forked: the parent has JAX and CUDA threads). A spawned child
normally re-imports the parent's main script first; jaxrender's workers need nothing from it,
so ``main_hidden`` keeps a user's script without a ``__main__`` guard from running again in
each worker. Kept free of heavy imports so that every worker pool can use it.
"""

from __future__ import annotations

import contextlib
import sys
import types


@contextlib.contextmanager
def main_hidden():
    """While workers start, show ``multiprocessing.spawn`` a main module with neither a file
    nor a spec, so a spawned child does not import (and run) the parent's main script. Pickling
    under it also refuses anything that lives in ``__main__``."""
    main = sys.modules.get("__main__")
    sys.modules["__main__"] = types.ModuleType("__main__")
    try:
        yield
    finally:
        if main is None:
            del sys.modules["__main__"]
        else:
            sys.modules["__main__"] = main
