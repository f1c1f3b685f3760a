#!/usr/bin/env python3
"""Every header and library the robot's targets build with comes from a
package of packaging/robot-client/build-depends.txt or one it depends on.

    robot_build_packages.py --source SRC --build BUILD [--list FILE]

The robot's targets are those an INSPECT_ROBOT_ONLY configure (the arm64
cross build of scripts/cross_pi.sh) makes: this configures one into a scratch
folder (no build) and reads its objects and link lines. Their headers come
from BUILD's dependency log (`ninja -t deps`, the same objects built for the
host), their libraries from the link lines; dpkg names each file's package.
A package outside the list and its dependencies (the closure of Depends and
Pre-Depends, as mmdebstrap extracts it for the sysroot) is a break the arm64
build would hit at configure or compile time: the test fails naming the file,
the object or program that needs it and the package to add (docs/deploy.md).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

LIB_DIRS = ["/usr/lib/x86_64-linux-gnu", "/lib/x86_64-linux-gnu", "/usr/lib", "/lib"]


def read_list(path):
    with open(path) as f:
        return [line.split()[0] for line in f if re.match(r"[a-z]", line)]


def robot_only_ninja(src, build, scratch):
    """The build.ninja of an INSPECT_ROBOT_ONLY configure of src, with build's compilers."""
    cache = {}
    with open(os.path.join(build, "CMakeCache.txt")) as f:
        for line in f:
            m = re.match(r"(CMAKE_CXX_COMPILER|CMAKE_C_COMPILER|CMAKE_BUILD_TYPE):[A-Z]+=(.*)", line)
            if m:
                cache[m.group(1)] = m.group(2)
    args = ["cmake", "-S", src, "-B", scratch, "-G", "Ninja", "-DINSPECT_ROBOT_ONLY=ON"]
    args += ["-D%s=%s" % (k, v) for k, v in cache.items() if v]
    r = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        sys.exit("robot_build_packages: the INSPECT_ROBOT_ONLY configure failed:\n" + r.stdout[-3000:])
    with open(os.path.join(scratch, "build.ninja")) as f:
        return f.read()


def objects_and_links(ninja_text):
    """The robot build's object files and, per linked program, its libraries."""
    objects = set()
    links = {}
    current = None
    for line in ninja_text.splitlines():
        m = re.match(r"build (\S+?\.o): C(XX)?_COMPILER__", line)
        if m:
            objects.add(m.group(1))
            current = None
            continue
        m = re.match(r"build (\S+)[^:]*: C(XX)?_(EXECUTABLE|SHARED_LIBRARY)_LINKER__", line)
        if m:
            current = m.group(1)
            continue
        if line.startswith("build "):
            current = None
        elif current and line.strip().startswith("LINK_LIBRARIES ="):
            links[current] = line.split("=", 1)[1].split()
    return objects, links


def resolve_library(token):
    """An absolute library path for a link-line token, or None (the project's own, flags)."""
    if token.startswith("/") and re.search(r"\.(so(\.[0-9.]+)?|a)$", token):
        return token
    m = re.match(r"-l(\S+)$", token)
    if m:
        for d in LIB_DIRS:
            for name in ("lib%s.so" % m.group(1), "lib%s.a" % m.group(1)):
                if os.path.exists(os.path.join(d, name)):
                    return os.path.join(d, name)
    return None


def host_headers(build, objects):
    """Per robot object, the system headers its host compile read (ninja's deps log)."""
    out = subprocess.run(["ninja", "-C", build, "-t", "deps"], stdout=subprocess.PIPE, text=True,
                         check=True).stdout
    headers = {}
    current = None
    for line in out.splitlines():
        if line and not line.startswith(" "):
            obj = line.split(":", 1)[0]
            current = obj if obj in objects else None
            if current:
                headers.setdefault(current, set())
        elif current and line.strip():
            path = line.strip()
            if path.startswith("/usr/") or path.startswith("/lib"):
                headers[current].add(os.path.normpath(path))
    return headers


def owners(paths):
    """dpkg's package of each path (a path dpkg does not know: tried again with symlinks resolved)."""
    found = {}
    paths = sorted(paths)
    for start in range(0, len(paths), 500):
        chunk = paths[start:start + 500]
        r = subprocess.run(["dpkg-query", "-S"] + chunk, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
        for line in r.stdout.splitlines():
            pkgs, _, path = line.partition(": ")
            if path in chunk:
                found[path] = {p.strip().split(":")[0] for p in pkgs.split(",")}
    missing = [p for p in paths if p not in found]
    again = {os.path.realpath(p): p for p in missing if os.path.realpath(p) != p}
    if again:
        r = subprocess.run(["dpkg-query", "-S"] + sorted(again), stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True)
        for line in r.stdout.splitlines():
            pkgs, _, path = line.partition(": ")
            if path in again:
                found[again[path]] = {p.strip().split(":")[0] for p in pkgs.split(",")}
    return found


def installed_packages():
    """dpkg's installed packages: each one's Depends and Pre-Depends, and who provides what."""
    out = subprocess.run(["dpkg-query", "-W", "-f", "${Package}\t${Depends}, ${Pre-Depends}\t${Provides}\n"],
                         stdout=subprocess.PIPE, text=True, check=True).stdout
    depends, provided_by = {}, {}
    for line in out.splitlines():
        pkg, deps, provides = (line.split("\t") + ["", ""])[:3]
        depends[pkg] = deps
        for p in provides.split(","):
            name = p.split("(")[0].strip()
            if name:
                provided_by.setdefault(name, set()).add(pkg)
    return depends, provided_by


def closure(roots, db):
    """The installed packages that roots pull in through Depends and Pre-Depends."""
    depends, provided_by = db
    seen, todo = set(), list(roots)
    while todo:
        pkg = todo.pop()
        if pkg in seen:
            continue
        seen.add(pkg)
        for group in depends.get(pkg, "").split(","):
            for alt in group.split("|"):
                name = alt.split("(")[0].strip().split(":")[0]
                if not name:
                    continue
                for real in ({name} if name in depends else set()) | provided_by.get(name, set()):
                    todo.append(real)
    return seen


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--source", required=True)
    ap.add_argument("--build", required=True)
    ap.add_argument("--list", help="the package list (default: SRC/packaging/robot-client/build-depends.txt)")
    a = ap.parse_args()
    t0 = time.monotonic()
    src, build = os.path.abspath(a.source), os.path.abspath(a.build)
    list_file = a.list or os.path.join(src, "packaging/robot-client/build-depends.txt")
    listed = read_list(list_file)
    db = installed_packages()
    scratch = tempfile.mkdtemp(prefix="robot-only-configure-")
    try:
        objects, links = objects_and_links(robot_only_ninja(src, build, scratch))
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    headers = host_headers(build, objects)
    unbuilt = sorted(objects - set(headers))
    if unbuilt:
        sys.exit("robot_build_packages: %d of the robot's %d objects are not in %s's dependency log "
                 "(build it first), e.g. %s" % (len(unbuilt), len(objects), build, unbuilt[0]))
    needed = {}  # path -> the first object or program that needs it
    for obj, paths in sorted(headers.items()):
        for p in paths:
            needed.setdefault(p, obj)
    n_libs = 0
    for program, tokens in sorted(links.items()):
        for t in tokens:
            lib = resolve_library(t)
            if lib:
                n_libs += 1
                needed.setdefault(lib, program)
    owner = owners(needed)
    allowed = closure(listed, db)
    missing = {}
    for path, user in sorted(needed.items()):
        pkgs = owner.get(path)
        if pkgs and not (pkgs & allowed):
            missing.setdefault("/".join(sorted(pkgs)), []).append((path, user))
    unowned = sorted(p for p in needed if p not in owner)
    print("robot_build_packages: %d robot objects and %d programs (INSPECT_ROBOT_ONLY), %d system files "
          "(%d library references), %d packages listed in %s, %d with their dependencies; %.1f s"
          % (len(objects), len(links), len(needed), n_libs, len(listed), os.path.relpath(list_file, src),
             len(allowed), time.monotonic() - t0))
    for p in unowned:
        print("robot_build_packages: note: %s (needed by %s) belongs to no package" % (p, needed[p]))
    for p in listed:
        if p not in db[0]:
            print("robot_build_packages: %s is listed but not installed on this host (scripts/setup.sh "
                  "installs it)" % p)
    if missing:
        for pkg, uses in sorted(missing.items()):
            path, user = uses[0]
            print("robot_build_packages: FAIL %s is in %s, which %s neither names nor pulls in: the arm64 "
                  "sysroot (scripts/cross_pi.sh) would not have it; needed by %s (%d files of that package); "
                  "add %s to the list" % (path, pkg, os.path.relpath(list_file, src), user, len(uses), pkg))
        return 1
    print("robot_build_packages: every header and library the robot's targets use is in the list's packages")
    return 0


if __name__ == "__main__":
    sys.exit(main())
