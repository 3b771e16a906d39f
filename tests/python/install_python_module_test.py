"""scripts/install_python_module.py: `import rths` from any interpreter that can load the build's
module, offline. Each test makes a fresh venv (no pip, no system site packages, so nothing but
what the script installs is seen), installs with the documented command and imports rths in it
from an empty folder with nothing but the venv's own paths. Interpreters other than Debian's are
pyenv's ($PYENV_ROOT or ~/.pyenv); a test needing one this machine lacks is skipped, naming it.
Run from ctest (python_install_module) with RTHS_SOURCE_DIR and RTHS_BINARY_DIR set."""
import glob
import os
import subprocess
from pathlib import Path

import pytest

SOURCE = Path(os.environ["RTHS_SOURCE_DIR"])
BINARY = Path(os.environ["RTHS_BINARY_DIR"])
SCRIPT = SOURCE / "scripts/install_python_module.py"
DEBIAN_PYTHON = "/usr/bin/python3"
SDOF = ("import rths; r = rths.sdof(period=0.5, zeta=0.05, "
        "motion=rths.data_path('ground_motions', 'RSN175_IMPVALL.H_H-E12140.AT2'), delay=0.014, "
        "experimental_fraction=1/3); print(r['verdict']['status'], r['delayed_m'].max() > 0, rths.__file__)")


def clean_env(tmp_path):
    """No PYTHONPATH (the suite's points at the build) and no pyenv shims."""
    return {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "LANG": "C.UTF-8"}


def run(command, tmp_path, cwd=None):
    return subprocess.run([str(c) for c in command], cwd=cwd or tmp_path, env=clean_env(tmp_path),
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=300)


def fresh_venv(base_python, tmp_path):
    venv = tmp_path / "venv"
    done = run([base_python, "-m", "venv", "--without-pip", venv], tmp_path)
    assert done.returncode == 0, done.stderr
    return venv / "bin/python"


def ext_suffix(python):
    return subprocess.run([python, "-c", "import sysconfig; print(sysconfig.get_config_var('EXT_SUFFIX'))"],
                          stdout=subprocess.PIPE, text=True, check=True).stdout.strip()


def pyenv_pythons():
    root = Path(os.environ.get("PYENV_ROOT", Path.home() / ".pyenv"))
    return sorted(glob.glob(str(root / "versions/3.*/bin/python3")))


def pyenv_python(same_abi):
    """A pyenv interpreter whose extension suffix is (or is not) Debian's python3's."""
    debian = ext_suffix(DEBIAN_PYTHON)
    for python in pyenv_pythons():
        if (ext_suffix(python) == debian) == same_abi:
            return python
    pytest.skip(f"no pyenv python3 {'with' if same_abi else 'without'} Debian's ABI {debian} here")


def assert_sdof_runs_from_the_venv(python, tmp_path):
    empty = tmp_path / "elsewhere"
    empty.mkdir()
    done = run([python, "-c", SDOF], tmp_path, cwd=empty)
    assert done.returncode == 0, done.stderr
    status, moved, module = done.stdout.split()
    assert (status, moved) == ("completed", "True")
    assert Path(module).is_relative_to(tmp_path / "venv"), module


def test_a_venv_of_debians_python_gets_rths_and_runs_an_sdof_test(tmp_path):
    python = fresh_venv(DEBIAN_PYTHON, tmp_path)
    before = run([python, "-c", "import rths"], tmp_path)
    assert "ModuleNotFoundError" in before.stderr  # the venv sees nothing of the system's
    done = run([python, SCRIPT, "--build", BINARY, "--system-numpy"], tmp_path)
    assert done.returncode == 0, done.stderr
    assert "installed rths" in done.stdout and "NumPy" in done.stdout
    assert_sdof_runs_from_the_venv(python, tmp_path)
    again = run([python, SCRIPT, "--build", BINARY, "--system-numpy"], tmp_path)
    assert again.returncode == 0, again.stderr  # a second install replaces the first


def test_without_numpy_the_install_is_refused_naming_the_offline_fix(tmp_path):
    python = fresh_venv(DEBIAN_PYTHON, tmp_path)
    done = run([python, SCRIPT, "--build", BINARY], tmp_path)
    assert done.returncode == 2, done.stdout + done.stderr
    assert "NumPy does not import" in done.stderr and "--system-numpy" in done.stderr
    assert not glob.glob(str(tmp_path / "venv/lib/python3*/site-packages/rths")), "written anyway"


def test_pyenvs_python_of_the_same_abi_gets_rths_and_runs_an_sdof_test(tmp_path):
    python = fresh_venv(pyenv_python(same_abi=True), tmp_path)
    done = run([python, SCRIPT, "--build", BINARY, "--system-numpy"], tmp_path)
    assert done.returncode == 0, done.stderr
    assert_sdof_runs_from_the_venv(python, tmp_path)


def test_another_python_version_is_refused_naming_it_and_what_it_needs(tmp_path):
    base = pyenv_python(same_abi=False)
    python = fresh_venv(base, tmp_path)
    version = run([python, "-c", "import sys; print('%d.%d' % sys.version_info[:2])"], tmp_path).stdout.strip()
    done = run([python, SCRIPT, "--build", BINARY, "--system-numpy"], tmp_path)
    assert done.returncode == 2, done.stdout + done.stderr
    assert f"Python {version}" in done.stderr and "Python.h" in done.stderr
    assert "-DPython3_EXECUTABLE=" in done.stderr
    assert not glob.glob(str(tmp_path / "venv/lib/python3*/site-packages/rths")), "written anyway"


def test_a_folder_without_a_built_module_is_refused(tmp_path):
    done = run([DEBIAN_PYTHON, SCRIPT, "--build", tmp_path, "--target", tmp_path / "site"], tmp_path)
    assert done.returncode == 2
    assert "no built module" in done.stderr
