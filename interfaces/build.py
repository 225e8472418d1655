"""Build the ROS interface packages that have no PyPI wheel into the venv.

`tf2_msgs` (for /tf) and `simulation_interfaces` (the ROS simulator
standard) are generated from their definition files, kept verbatim under
interfaces/<package>/, with the ROS wheels' own rosidl generators and plain
CMake (no colcon, no apt), and installed into the venv prefix, where rclpy
finds them with nothing else set (shared/ROS_INTERFACES.md).

    .venv/bin/python interfaces/build.py            # what `make install` runs
    .venv/bin/python interfaces/build.py --force    # rebuild even if unchanged
    .venv/bin/python interfaces/build.py --cxx      # also the C++ headers

A stamp in the venv holds the hash of the definitions and of this build's
files: when it is unchanged (and the packages import) nothing is rebuilt.
Needs cmake >= 3.16 and a C/C++ compiler; about 1.5 min of CPU for both
packages without the C++ generators.
"""

import argparse
import hashlib
import importlib
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
PACKAGES = ("tf2_msgs", "simulation_interfaces")  # in dependency order
STAMP_NAME = ".interfaces-stamp"
# The wheels' exported Python-generator CMake files name the include
# directories of the interpreter the wheels were built with.
_FOREIGN_INCLUDES = re.compile(r'"/opt/python/cp3\d+-cp3\d+/include/python3\.\d+;[^"]*numpy[^"]*"')


class BuildError(RuntimeError):
    pass


def definitions_hash(cxx=False):
    """sha256 over every file that decides what is built, by relative path."""
    h = hashlib.sha256()
    for path in sorted(p for p in HERE.rglob("*") if p.is_file() and "__pycache__" not in p.parts):
        h.update(str(path.relative_to(HERE)).encode() + b"\0")
        h.update(path.read_bytes() + b"\0")
    h.update(f"cxx={bool(cxx)};python={sys.version_info[:2]}".encode())
    return h.hexdigest()


def venv_prefix():
    return Path(sys.prefix)


def up_to_date(prefix, digest):
    stamp = prefix / STAMP_NAME
    if not stamp.is_file() or stamp.read_text().strip() != digest:
        return False
    return all(_importable(pkg) for pkg in PACKAGES)


def _importable(package):
    # A child process: the ROS start-up hook sets LD_LIBRARY_PATH only for
    # a fresh interpreter, and this one may have imported a stale copy.
    probe = f"import {package}.msg"
    return subprocess.run([sys.executable, "-c", probe], capture_output=True).returncode == 0


def fix_exported_includes(prefix):
    """Point the wheels' exported include directories at this interpreter's
    headers and numpy's; configure fails on the foreign paths otherwise."""
    import numpy

    local = f'"{sysconfig.get_paths()["include"]};{numpy.get_include()}"'
    fixed = 0
    for path in (prefix / "share").glob("*/cmake/*__rosidl_generator_pyExport.cmake"):
        text = path.read_text()
        new = _FOREIGN_INCLUDES.sub(local, text)
        if new != text:
            path.write_text(new)
            fixed += 1
    return fixed


def _run(cmd, env, log):
    log.write(f"$ {' '.join(map(str, cmd))}\n")
    log.flush()
    done = subprocess.run([str(c) for c in cmd], env=env, stdout=log, stderr=subprocess.STDOUT)
    if done.returncode != 0:
        raise BuildError(f"{cmd[0]} failed (exit {done.returncode}); see {log.name}")


def build_package(package, prefix, build_root, cxx, jobs):
    source = HERE / package
    build = build_root / package
    if build.exists():
        shutil.rmtree(build)
    build.mkdir(parents=True)
    env = dict(os.environ)
    # CMake finds the generators and type supports through the ament index.
    env["AMENT_PREFIX_PATH"] = os.pathsep.join(filter(None, [str(prefix), env.get("AMENT_PREFIX_PATH", "")]))
    env["PATH"] = os.pathsep.join([str(prefix / "bin"), env.get("PATH", "")])
    configure = [
        "cmake", "-S", source, "-B", build,
        f"-DCMAKE_PREFIX_PATH={prefix}", f"-DCMAKE_INSTALL_PREFIX={prefix}",
        f"-DPython3_EXECUTABLE={sys.executable}", "-DBUILD_TESTING=OFF",
        f"-DINTERFACES_CXX={'ON' if cxx else 'OFF'}", "-DCMAKE_BUILD_TYPE=Release",
    ]  # fmt: skip
    with open(build_root / f"{package}.log", "w") as log:
        _run(configure, env, log)
        _run(["cmake", "--build", build, "--parallel", str(jobs)], env, log)
        _run(["cmake", "--install", build], env, log)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--force", action="store_true", help="rebuild even when the stamp matches")
    p.add_argument("--cxx", action="store_true", help="also generate the C++ headers and type supports")
    p.add_argument("--build-dir", default=str(HERE.parent / "build" / "interfaces"))
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    args = p.parse_args(argv)
    prefix = venv_prefix()
    digest = definitions_hash(args.cxx)
    if not args.force and up_to_date(prefix, digest):
        print(f"interfaces: {', '.join(PACKAGES)} up to date in {prefix}")
        return 0
    if shutil.which("cmake") is None:
        print("interfaces: cmake (3.16 or newer) and a C/C++ compiler are needed to build "
              f"{', '.join(PACKAGES)}", file=sys.stderr)  # fmt: skip
        return 2
    build_root = Path(args.build_dir)
    build_root.mkdir(parents=True, exist_ok=True)
    fixed = fix_exported_includes(prefix)
    if fixed:
        print(f"interfaces: pointed {fixed} exported CMake files at this interpreter's headers")
    (prefix / STAMP_NAME).unlink(missing_ok=True)
    for package in PACKAGES:
        start = time.monotonic()
        print(f"interfaces: building {package} into {prefix} ...", flush=True)
        try:
            build_package(package, prefix, build_root, args.cxx, args.jobs)
        except BuildError as exc:
            print(f"interfaces: {package}: {exc}", file=sys.stderr)
            return 1
        print(f"interfaces: {package} built in {time.monotonic() - start:.0f} s", flush=True)
    importlib.invalidate_caches()
    missing = [pkg for pkg in PACKAGES if not _importable(pkg)]
    if missing:
        print(f"interfaces: built but not importable: {', '.join(missing)}", file=sys.stderr)
        return 1
    (prefix / STAMP_NAME).write_text(digest + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
