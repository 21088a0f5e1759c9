"""Open3D, imported without its ``open3d.ml`` and ``open3d.visualization`` subpackages.

``import open3d`` (0.19) also imports ``open3d.ml``, whose dataset loaders import
scikit-learn and SciPy's statistics (~1.0 s), and ``open3d.visualization``, whose
Plotly drawing imports Dash and pandas (~0.3 s): 2.1-2.7 s of CPU in every process
that needs Open3D (the register stage's main process and its edge-ICP workers, the
simulator), of which floorscan uses neither part. :func:`load` imports the package
with those two names held by empty placeholder modules, so ``open3d/__init__.py``
binds the placeholders instead of importing them (0.8-1.0 s; the compiled
``open3d.cpu.pybind`` with ``geometry``, ``pipelines``, ``io``, ``t`` and the rest is
loaded as usual). The placeholders are removed from ``sys.modules`` afterwards, so a
later ``import open3d.visualization`` imports the real subpackage.

Use ``from floorscan.o3d import o3d`` (or :func:`load`) instead of ``import open3d``.
A process that imported Open3D before gets that module unchanged. If the guarded
import fails (an Open3D whose ``__init__`` needs these subpackages), Open3D is
imported plainly.
"""

from __future__ import annotations

import sys
import types

# The subpackages open3d/__init__.py imports that floorscan never uses.
SKIPPED = ("open3d.ml", "open3d.visualization")


def load() -> types.ModuleType:
    """The ``open3d`` module, imported without :data:`SKIPPED` if not imported yet.

    Raises
    ------
    ImportError
        When Open3D is not installed (``pip install open3d``; on Debian it also needs
        the package ``libusb-1.0-0``).
    """
    if "open3d" in sys.modules:
        return sys.modules["open3d"]
    placeholders = {name: types.ModuleType(name) for name in SKIPPED if name not in sys.modules}
    sys.modules.update(placeholders)
    try:
        import open3d
    except ImportError:
        for name in list(sys.modules):
            if name == "open3d" or name.startswith("open3d."):
                del sys.modules[name]
        placeholders = {}
        import open3d  # noqa: F811  (the plain import; raises if Open3D is missing)
    finally:
        for name, module in placeholders.items():
            if sys.modules.get(name) is module:
                del sys.modules[name]
    return open3d


o3d = load()
