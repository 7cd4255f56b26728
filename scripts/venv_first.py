"""Let the project venv's own packages win over Debian's, while Debian's rospy stays visible.

The venv is made with --system-site-packages so that rospy (Debian only) imports. Its site-packages come
before /usr/lib/python3/dist-packages on sys.path, which is enough for regular packages, but not for
namespace packages: the path finder keeps scanning past a namespace portion, and a *regular* package of
the same name later on sys.path wins. Debian's python3-zope.interface ships zope/__init__.py (and a
-nspkg.pth that seeds sys.modules["zope"] with Debian's directory at start-up), so it shadows the venv's
namespace `zope` and pip's twisted then fails at import.

bootstrap.sh installs this file into the venv's site-packages as _cell_venv_first.py with a .pth line
that imports it. The venv's .pth files run before the system's, so this runs first and creates each of
the venv's top-level namespace packages as a namespace module whose portions list the venv's directory
first, then the same directory in the system site-packages. Debian's -nspkg.pth then finds the module
already there and only appends its directory (after ours). The venv's subpackages are found first;
Debian-only subpackages still import.
"""
from __future__ import annotations

import importlib.machinery
import importlib.util
import os
import site
import sys
import sysconfig

VENV_SITE = sysconfig.get_paths()["purelib"]


def venv_namespaces(site_dir: str) -> list[str]:
    """Top-level names that the venv holds as namespace portions (a directory without __init__.py)."""
    names = []
    for name in sorted(os.listdir(site_dir)):
        d = os.path.join(site_dir, name)
        if name.isidentifier() and os.path.isdir(d) and not os.path.exists(os.path.join(d, "__init__.py")) \
                and any(os.path.isdir(os.path.join(d, c)) and c.isidentifier() for c in os.listdir(d)):
            names.append(name)
    return names


def install(site_dir: str = VENV_SITE, system_dirs: list[str] | None = None) -> list[str]:
    """Seed sys.modules with the venv's namespace packages; returns their names."""
    if system_dirs is None:
        system_dirs = [d for d in site.getsitepackages([sys.base_prefix]) if os.path.isdir(d)]
    seeded = []
    for name in venv_namespaces(site_dir):
        if name in sys.modules:
            continue
        portions = [os.path.join(site_dir, name)]
        portions += [os.path.join(d, name) for d in system_dirs if os.path.isdir(os.path.join(d, name))]
        spec = importlib.machinery.ModuleSpec(name, None, is_package=True)
        spec.submodule_search_locations = portions
        sys.modules[name] = importlib.util.module_from_spec(spec)
        seeded.append(name)
    return seeded


if sys.prefix != sys.base_prefix:  # only inside a venv
    install()
