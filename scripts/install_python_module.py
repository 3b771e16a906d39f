"""Installs the `rths` Python module for the interpreter that runs this script (a venv, pyenv,
conda or Debian's python3), from what the build made; nothing is downloaded.

    /path/to/python scripts/install_python_module.py [--build DIR] [--target DIR] [--system-numpy]

The build's package (DIR/python/rths: the compiled rths._rths and the Python layer; DIR defaults
to the clone's build/) is copied into the interpreter's site folder (sysconfig platlib: a venv's
own site-packages), or into --target. The compiled part is made for one Python ABI (Debian's
python3, CPython 3.11: extension suffix .cpython-311-x86_64-linux-gnu.so); an interpreter that
cannot load that suffix is refused, naming its version and the build that would serve it.
rths returns NumPy arrays: an interpreter without NumPy is refused, unless --system-numpy lends
it Debian's python3-numpy (same ABI only): a folder rths_system_numpy/ holding a link to
/usr/lib/python3/dist-packages/numpy, named in rths_system_numpy.pth, after the interpreter's own
folders (a NumPy installed later in the venv comes first). Nothing else of Debian's is seen.
After copying, the interpreter imports rths in isolated mode (-I: no PYTHONPATH, no current
folder) from an empty folder; an install that does not import is removed again.

Exit: 0 installed and imported; 2 this interpreter cannot be served as it is (another ABI, no
NumPy, no built module), nothing written; 3 the site folder cannot be written, or the installed
module does not import (removed again).
"""
import argparse
import glob
import importlib.machinery
import os
import platform
import shutil
import subprocess
import sys
import sysconfig
import tempfile

CLONE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEBIAN_NUMPY = "/usr/lib/python3/dist-packages/numpy"
NUMPY_LINK_DIR = "rths_system_numpy"


class Refused(Exception):
    """Why this interpreter is not served, and the exit code that says which kind."""

    def __init__(self, message, code):
        super().__init__(message)
        self.code = code


def interpreter():
    """"<executable> (CPython 3.11.7, extension suffix .cpython-311-x86_64-linux-gnu.so)"."""
    return (f"{sys.executable} ({platform.python_implementation()} {platform.python_version()}, "
            f"extension suffix {sysconfig.get_config_var('EXT_SUFFIX')})")


def built_package(build):
    """The build's package folder and its compiled module's file name."""
    package = os.path.join(build, "python", "rths")
    compiled = sorted(glob.glob(os.path.join(package, "_rths*.so")))
    if not compiled or not os.path.isfile(os.path.join(package, "__init__.py")):
        raise Refused(f"no built module in {package}: build it first "
                      f"(cmake --build {build} --target rths_python)", 2)
    return package, os.path.basename(compiled[0])


def check_abi(compiled_name):
    """Refuses an interpreter that cannot load the compiled module's extension suffix."""
    suffix = compiled_name[len("_rths"):]
    if suffix in importlib.machinery.EXTENSION_SUFFIXES:
        return
    version = "{}.{}".format(*sys.version_info[:2])
    build = os.path.join(CLONE, "build-py" + version)
    headers = os.path.join(sysconfig.get_paths()["include"], "Python.h")
    have = "present" if os.path.isfile(headers) else "missing: install this Python's development headers"
    raise Refused(
        f"{interpreter()} cannot load the build's module {compiled_name} (made for {suffix}, "
        f"Debian's python3 unless the build was told otherwise). A module for Python {version} is "
        f"compiled against its own headers ({headers}: {have}) in a build of its own:\n"
        f"  cmake -S {CLONE} -B {build} -G Ninja -DCMAKE_BUILD_TYPE=Release "
        f"-DPython3_EXECUTABLE={sys.executable}\n"
        f"  cmake --build {build} --target rths_python\n"
        f"  {sys.executable} {os.path.abspath(__file__)} --build {build}\n"
        f"(the libraries compile again, minutes; Debian 12's pybind11-dev 2.10 is made for CPython "
        f"3.6-3.11; NumPy must be installed for Python {version}, which --system-numpy cannot "
        f"lend). Or use a venv made from Debian's python3: /usr/bin/python3 -m venv DIR.", 2)


def numpy_source(lend_debian):
    """Where this interpreter's NumPy comes from: its own, or Debian's (lent); refuses when none."""
    # In isolated mode, as rths will be imported: a NumPy that only PYTHONPATH names is not its own.
    own = subprocess.run([sys.executable, "-I", "-c", "import numpy"], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    if own.returncode == 0:
        return "its own"
    if not lend_debian:
        raise Refused(
            f"NumPy does not import in {interpreter()}, and rths returns NumPy arrays: install it "
            f"({sys.executable} -m pip install numpy, from an index or a wheel), or, offline, "
            f"rerun with --system-numpy to lend it Debian's python3-numpy ({DEBIAN_NUMPY}).", 2)
    compiled = glob.glob(os.path.join(DEBIAN_NUMPY, "core", "_multiarray_umath*.so"))
    if not compiled:
        raise Refused(f"--system-numpy: no Debian NumPy at {DEBIAN_NUMPY} "
                      f"(apt-get install python3-numpy)", 2)
    suffix = os.path.basename(compiled[0])[len("_multiarray_umath"):]
    if suffix not in importlib.machinery.EXTENSION_SUFFIXES:
        raise Refused(f"--system-numpy: Debian's NumPy is built for {suffix}, which "
                      f"{interpreter()} cannot load", 2)
    return f"Debian's, lent ({DEBIAN_NUMPY})"


def lend_debian_numpy(site):
    """rths_system_numpy/numpy -> Debian's NumPy, on the path through rths_system_numpy.pth."""
    folder = os.path.join(site, NUMPY_LINK_DIR)
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    os.symlink(DEBIAN_NUMPY, os.path.join(folder, "numpy"))
    with open(os.path.join(site, NUMPY_LINK_DIR + ".pth"), "w") as pth:
        pth.write(folder + "\n")


def copy_package(package, site):
    """The package into site/rths, whole or not at all (copied beside it, then renamed)."""
    final = os.path.join(site, "rths")
    partial = os.path.join(site, "rths.partial")
    shutil.rmtree(partial, ignore_errors=True)
    shutil.copytree(package, partial, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.rmtree(final, ignore_errors=True)
    os.rename(partial, final)
    return final


def installed_paths(site, lent_numpy):
    paths = [os.path.join(site, "rths")]
    if lent_numpy:
        paths += [os.path.join(site, NUMPY_LINK_DIR), os.path.join(site, NUMPY_LINK_DIR + ".pth")]
    return paths


def remove(paths):
    for path in paths:
        if os.path.isdir(path) and not os.path.islink(path):
            shutil.rmtree(path, ignore_errors=True)
        elif os.path.lexists(path):
            os.remove(path)


def imported_version(site):
    """rths's version as the interpreter imports it in isolated mode from an empty folder;
    raises Refused (exit 3) when it does not import, or not from `site`."""
    probe = ("import os, sys, numpy, rths; "
             "print(rths.__version__, numpy.__version__, os.path.dirname(os.path.dirname(rths.__file__)))")
    with tempfile.TemporaryDirectory() as empty:
        done = subprocess.run([sys.executable, "-I", "-c", probe], cwd=empty, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, universal_newlines=True)
    if done.returncode != 0:
        raise Refused(f"the installed module does not import in {interpreter()}:\n{done.stdout}", 3)
    version, numpy_version, found_in = done.stdout.split()
    if os.path.realpath(found_in) != os.path.realpath(site):
        raise Refused(f"{sys.executable} imports rths from {found_in}, not from {site}: "
                      f"an earlier one comes first on its path", 3)
    return version, numpy_version


def install(build, site, lend_debian):
    package, compiled = built_package(build)
    check_abi(compiled)
    numpy_from = numpy_source(lend_debian)
    lent = numpy_from.startswith("Debian")
    try:
        os.makedirs(site, exist_ok=True)
        copy_package(package, site)
        if lent:
            lend_debian_numpy(site)
    except OSError as e:
        raise Refused(f"cannot write {site}: {e} (a venv's own site folder, or --target DIR)", 3)
    try:
        version, numpy_version = imported_version(site)
    except Refused:
        remove(installed_paths(site, lent))
        raise
    print(f"installed rths {version} for {interpreter()} in {os.path.join(site, 'rths')}; "
          f"NumPy {numpy_version}, {numpy_from}; imports with nothing but its own paths")
    print("to remove: rm -r " + " ".join(installed_paths(site, lent)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", default=os.path.join(CLONE, "build"),
                        help="the build folder (default: the clone's build/)")
    parser.add_argument("--target", default=sysconfig.get_path("platlib"),
                        help="site folder to install into, one the interpreter reads at start "
                             "(default: its own, %(default)s)")
    parser.add_argument("--system-numpy", action="store_true",
                        help="lend an interpreter without NumPy Debian's python3-numpy (same ABI only)")
    args = parser.parse_args()
    try:
        install(os.path.abspath(args.build), os.path.abspath(args.target), args.system_numpy)
    except Refused as e:
        print(f"install_python_module: {e}", file=sys.stderr)
        return e.code
    return 0


if __name__ == "__main__":
    sys.exit(main())
