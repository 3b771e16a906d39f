"""`cmake --install` puts the module where Debian's python3 finds it: staged with DESTDIR, the
installed package imports from an empty folder with nothing but Debian's own paths (and NumPy with
it), and rths.data_path names a shipped record. Run from ctest (python_installed_module)."""
import os
import subprocess
from pathlib import Path

BINARY = Path(os.environ["RTHS_BINARY_DIR"])
DEBIAN_PYTHON = "/usr/bin/python3"


def test_the_installed_module_imports_from_any_folder_with_debians_python(tmp_path):
    stage = tmp_path / "stage"
    subprocess.run(["cmake", "--install", str(BINARY)], check=True, stdout=subprocess.DEVNULL,
                   env=dict(os.environ, DESTDIR=str(stage)))
    platlib = subprocess.run([DEBIAN_PYTHON, "-c", "import sysconfig; print(sysconfig.get_path('platlib'))"],
                             check=True, stdout=subprocess.PIPE, text=True).stdout.strip()
    staged = stage / platlib.lstrip("/")
    assert (staged / "rths" / "__init__.py").is_file(), f"nothing installed under {platlib}"
    empty = tmp_path / "elsewhere"
    empty.mkdir()
    env = {"PATH": "/usr/bin:/bin", "PYTHONPATH": str(staged), "HOME": str(tmp_path)}
    probe = ("import rths, numpy; r = rths.data_path('ground_motions', 'RSN175_IMPVALL.H_H-E12140.AT2'); "
             "print(rths.__version__, numpy.__name__, r)")
    done = subprocess.run([DEBIAN_PYTHON, "-c", probe], cwd=empty, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True)
    assert done.returncode == 0, done.stdout
    assert "RSN175_IMPVALL.H_H-E12140.AT2" in done.stdout
