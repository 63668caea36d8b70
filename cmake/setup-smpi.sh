#!/usr/bin/env bash
# cmake/setup-smpi.sh [BUILD_DIR] [extra cmake args...] — the SimGrid SMPI build of coloc
# (docs/smpi.md): installs SimGrid (Debian: libsimgrid-dev) when missing, builds hypre
# from Debian's own source package with smpicc once (BUILD_DIR/hypre, ~3 minutes on 2 cores;
# one patch for the simulation, cmake/hypre-smpi-exchange.patch; Debian's compiler flags),
# then configures and builds coloc with -DCOLOC_SMPI=ON in BUILD_DIR (default: build-smpi).
# Run it after cmake/setup.sh (which installs the other dependencies). Idempotent.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build-smpi}
shift || true
mkdir -p "$build"
build=$(cd "$build" && pwd)

sudo=""
[[ $(id -u) -ne 0 ]] && sudo="sudo"
missing=()
for p in libsimgrid-dev; do  # smpicc, smpicxx, smpirun (it provides "simgrid")
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "coloc setup-smpi: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
    -o Dpkg::Options::=--force-unsafe-io \
    "${missing[@]}" >/dev/null
fi

# hypre with smpicc: the version of Debian's libhypre-dev (the Open MPI build's), from Debian's
# source package, through a private deb-src list (the system's lists are not touched).
# One change to hypre's sources for the simulation (cmake/hypre-smpi-exchange.patch: its assumed-
# partition exchange probes instead of testing, see the patch's header); a new patch rebuilds it.
hypre=$build/hypre
lib=$hypre/install/lib/libHYPRE.a
patch_file=$root/cmake/hypre-smpi-exchange.patch
# hypre's compiler flags: Debian's (dpkg-buildflags) with the -O3 its rules append
# (DEB_CFLAGS_MAINT_APPEND), so a simulated burst runs the code the Open MPI build links.
hypre_cflags="$(dpkg-buildflags --get CFLAGS 2>/dev/null | sed "s/-ffile-prefix-map=[^ ]*//") -O3"
stamp=$( (cat "$patch_file"; echo "$hypre_cflags") | sha256sum | cut -c1-16)
if [[ ! -f $lib || $(cat "$hypre/patch.stamp" 2>/dev/null) != "$stamp" ]]; then
  version=$(dpkg-query -W -f='${Version}' libhypre-dev 2>/dev/null || true)
  echo "coloc setup-smpi: building hypre ${version:-?} with smpicc in $hypre"
  rm -rf "$hypre" && mkdir -p "$hypre/apt/lists/partial" "$hypre/src"
  suite=$(. /etc/os-release && echo "${VERSION_CODENAME:-bookworm}")
  # The Debian archive apt already uses (a mirror ending in /debian; not -security, not a
  # third-party repository), else deb.debian.org.
  mirror=$(grep -rhoE '^(URIs:|deb) *https?://[^ ]+' /etc/apt/sources.list.d/ /etc/apt/sources.list \
             2>/dev/null | sed -E 's/^(URIs:|deb) *//' | grep -E '/debian/?$' | head -1 || true)
  cat > "$hypre/apt/src.sources" <<X
Types: deb-src
URIs: ${mirror:-http://deb.debian.org/debian}
Suites: $suite
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
X
  opts=(-o "Dir::Etc::sourcelist=$hypre/apt/src.sources" -o Dir::Etc::sourceparts=-
        -o "Dir::State::Lists=$hypre/apt/lists" -o Debug::NoDropPrivs=1)
  if ! (cd "$hypre/src" && apt-get "${opts[@]}" update -qq &&
          apt-get "${opts[@]}" source --download-only hypre >"$hypre/apt/source.log" 2>&1); then
    cat "$hypre/apt/source.log" 2>/dev/null || true
    echo "coloc setup-smpi: could not download Debian's hypre source from ${mirror:-deb.debian.org}" >&2
    exit 1
  fi
  tar xzf "$hypre"/src/hypre_*.orig.tar.gz -C "$hypre/src"
  cd "$hypre"/src/hypre-*/src
  git apply "$patch_file"  # git apply works outside a repository
  # SMPI_PRETEND_CC: autoconf's test programs must run as ordinary programs while configuring.
  SMPI_PRETEND_CC=1 ./configure CC=smpicc CXX=smpicxx CFLAGS="$hypre_cflags" \
    CXXFLAGS="$hypre_cflags" \
    --prefix="$hypre/install" --disable-fortran --enable-shared=no >"$hypre/configure.log" 2>&1 ||
    { tail -20 "$hypre/configure.log"; exit 1; }
  make -j "$(nproc)" >"$hypre/make.log" 2>&1 || { tail -20 "$hypre/make.log"; exit 1; }
  make install >>"$hypre/make.log" 2>&1
  echo "$stamp" >"$hypre/patch.stamp"
  cd "$root"
fi

if [[ ! -f $build/build.ninja || $# -gt 0 ]]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCOLOC_SMPI=ON \
        -DCOLOC_BUILD_BENCHMARKS=OFF -DHYPRE_LIBRARY="$lib" \
        -DHYPRE_INCLUDE_DIR="$hypre/install/include" -DPython3_EXECUTABLE=/usr/bin/python3 \
        "$@" >/dev/null
fi
cmake --build "$build" -j "$(nproc)"
