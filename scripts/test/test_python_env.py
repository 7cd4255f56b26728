"""The venv's own packages win over Debian's, and Debian's rospy stays visible (scripts/venv_first.py)."""
from __future__ import annotations

import json
import subprocess
import sysconfig
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
VENV_PY = ROOT / ".venv" / "bin" / "python"


def venv_python(code: str, *flags: str) -> dict:
    out = subprocess.run([str(VENV_PY), *flags, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                         timeout=60, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_venv_twisted_and_zope_win_and_rospy_is_visible() -> None:
    got = venv_python("""
        import json, zope, zope.interface, twisted, twisted.internet.task, roslibpy, rospy, OpenSSL, cryptography
        print(json.dumps({"zope_path": list(zope.__path__), "zope.interface": zope.interface.__file__,
                          "twisted": twisted.__file__, "rospy": rospy.__file__, "OpenSSL": OpenSSL.__file__,
                          "cryptography": cryptography.__file__}))
    """)
    venv = str(ROOT / ".venv")
    assert got["zope.interface"].startswith(venv)
    assert got["twisted"].startswith(venv)
    # Their dependencies too: Debian's pyOpenSSL with pip's cryptography fails at the first TLS import.
    assert got["OpenSSL"].startswith(venv) and got["cryptography"].startswith(venv)
    assert got["zope_path"][0].startswith(venv)
    assert got["rospy"].startswith("/usr/lib/python3/dist-packages/")


def test_a_debian_regular_zope_package_does_not_shadow_the_venv(tmp_path: Path) -> None:
    """As on a robot PC with python3-zope.interface: a regular `zope` package later on sys.path."""
    debian = tmp_path / "dist-packages"
    (debian / "zope" / "interface").mkdir(parents=True)
    (debian / "zope" / "__init__.py").write_text("")
    (debian / "zope" / "interface" / "__init__.py").write_text("raise ImportError('the old Debian zope.interface')\n")
    (debian / "zope" / "debianonly").mkdir()
    (debian / "zope" / "debianonly" / "__init__.py").write_text("")
    site_dir = sysconfig.get_paths(vars={"base": str(ROOT / ".venv"), "platbase": str(ROOT / ".venv")})["purelib"]
    # -S: no site processing, so this run sees only the two directories given here.
    code = f"""
        import json, sys
        sys.path[:0] = [{site_dir!r}, {str(ROOT / 'scripts')!r}]
        sys.path.append({str(debian)!r})
        if sys.argv[-1] == "hook":
            import venv_first
            venv_first.install({site_dir!r}, [{str(debian)!r}])
        try:
            import zope.interface
            where = zope.interface.__file__
        except ImportError as e:
            where = "ImportError: " + str(e)
        import zope.debianonly
        print(json.dumps({{"zope.interface": where}}))
    """
    def run(mode: str) -> dict:
        out = subprocess.run([str(VENV_PY), "-S", "-c", textwrap.dedent(code), mode], capture_output=True, text=True,
                             timeout=60)
        assert out.returncode == 0, out.stderr
        return json.loads(out.stdout.strip().splitlines()[-1])

    # Without the hook the Debian package wins (the failure robot PCs saw) ...
    assert run("plain")["zope.interface"].startswith("ImportError: the old Debian")
    # ... with it the venv's zope.interface is imported, and Debian-only subpackages still import.
    assert run("hook")["zope.interface"].startswith(site_dir)


def test_bootstrap_installs_the_hook_into_the_venv() -> None:
    site_dir = Path(venv_python("import json, sysconfig; print(json.dumps(sysconfig.get_paths()['purelib']))"))
    assert (site_dir / "_cell_venv_first.pth").read_text().strip() == "import _cell_venv_first"
    assert (site_dir / "_cell_venv_first.py").read_text() == (ROOT / "scripts" / "venv_first.py").read_text()
