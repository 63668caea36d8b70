#!/usr/bin/env bash
# bench/scripts/portable_bundle.sh [OUT.tar.xz] [DEST]
#
# Packs coloc for an x86-64 Linux machine that has no MPI, hypre or HDF5 (a bare image, a
# borrowed node): build/coloc and the benchmarks validate_model.py runs (bench_stream,
# bench_pingpong, bench_fv, bench_noise), Open MPI's runtime (orterun as mpirun, its MCA
# components without the fabric ones, PMIx), the SMPI build (build-smpi/coloc, SimGrid's
# smpimain and smpirun) when there is one, and every shared library they load, glibc included.
# Every ELF file is patched (patchelf: RPATH and interpreter) to load only from DEST/lib, so the
# target's own libraries, whatever their versions, are never mixed in. This is how
# bench/scripts/many_core_check.sh ran on a 16-core machine (docs/smpi.md). On the target:
#
#   mkdir -p DEST && tar -C DEST -xJf OUT.tar.xz && source DEST/env.sh
#   bench/scripts/many_core_check.sh out/many-core        # from a checkout of the same commit
#
# DEST must be the same absolute path on the target (default /tmp/colocdev). Shared-memory
# transport only (btl self,vader): one node. Needs patchelf (apt-get install patchelf).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
out=$(realpath -m "${1:-$root/out/coloc-portable.tar.xz}")
dest=${2:-/tmp/colocdev}
command -v patchelf >/dev/null || { echo "portable_bundle.sh: needs patchelf" >&2; exit 1; }
b=$(mktemp -d)
trap 'rm -rf "$b"' EXIT
mkdir -p "$b"/{bin,lib,openmpi3,pmix,hwloc,share,etc}
for f in coloc bench/bench_stream bench/bench_pingpong bench/bench_fv bench/bench_noise; do
  [[ -x $root/build/$f ]] || { echo "portable_bundle.sh: no build/$f (cmake/setup.sh)" >&2; exit 1; }
  cp -L "$root/build/$f" "$b/bin/"
done
cp -L /usr/bin/orterun /usr/bin/orted "$b/bin/"
ln -s orterun "$b/bin/mpirun"
ln -s orterun "$b/bin/mpiexec"
# MCA components, less those of fabrics a node without them cannot load
fabric='libibverbs|libfabric|libucp|libucs|libuct|libucm|libpsm|librdmacm|libcuda|libxpmem|libknem|libnl-|libpmi\.so|libpmi2'
for c in /usr/lib/x86_64-linux-gnu/openmpi/lib/openmpi3/*.so; do
  ldd "$c" | grep -Eq "$fabric|not found" || cp -L "$c" "$b/openmpi3/"
done
cp -L /usr/lib/x86_64-linux-gnu/pmix2/lib/pmix/*.so "$b/pmix/"
cp -r /usr/share/openmpi "$b/share/openmpi"
cp -r /usr/lib/x86_64-linux-gnu/pmix2/share/pmix "$b/share/pmix"
if [[ -e $root/build-smpi/coloc ]]; then
  mkdir -p "$b/smpi/bin" "$b/smpi/build"
  cp -L /usr/lib/x86_64-linux-gnu/simgrid/smpimain "$b/smpi/bin/"
  cp -L "$root/build-smpi/coloc" "$b/smpi/build/coloc"
  sed -e "s#/usr/lib/x86_64-linux-gnu/simgrid/smpimain#$dest/smpi/bin/smpimain#" \
      -e "s#/usr/bin/python3#python3#" -e "/^export LD_LIBRARY_PATH=/d" /usr/bin/smpirun \
      >"$b/smpi/bin/smpirun"
  chmod +x "$b/smpi/bin/smpirun"
fi
# every library the ELF files load (twice: the libraries' own needs), glibc and its loader too
needs() { ldd "$1" 2>/dev/null | awk '/=> \//{print $3}'; }
for pass in 1 2; do
  find "$b" -type f | while read -r e; do file -b "$e" | grep -q ELF && needs "$e"; done |
    sort -u | while read -r l; do [[ -e $b/lib/$(basename "$l") ]] || cp -L "$l" "$b/lib/"; done
done
cp -L /lib64/ld-linux-x86-64.so.2 "$b/lib/"
for l in libnss_files.so.2 libnss_dns.so.2 libresolv.so.2; do
  [[ -e /lib/x86_64-linux-gnu/$l ]] && cp -L "/lib/x86_64-linux-gnu/$l" "$b/lib/"
done
find "$b" -type f | while read -r e; do
  file -b "$e" | grep -q ELF || continue
  [[ $(basename "$e") == ld-linux-x86-64.so.2 ]] && continue
  patchelf --force-rpath --set-rpath "$dest/lib" "$e"
  if file -b "$e" | grep -q interpreter; then
    patchelf --set-interpreter "$dest/lib/ld-linux-x86-64.so.2" "$e"
  fi
done
cat >"$b/env.sh" <<EOF
# source $dest/env.sh: coloc's portable bundle (bench/scripts/portable_bundle.sh)
D=$dest
export PATH=\$D/bin:\$D/smpi/bin:\$PATH COLOC=\$D/bin/coloc BENCH=\$D/bin SMPI_BUILD=\$D/smpi/build
export OPAL_PREFIX=\$D OPAL_EXEC_PREFIX=\$D OPAL_BINDIR=\$D/bin OPAL_LIBDIR=\$D/lib
export OPAL_PKGLIBDIR=\$D/openmpi3 OPAL_PKGDATADIR=\$D/share/openmpi OPAL_DATADIR=\$D/share
export OPAL_DATAROOTDIR=\$D/share OPAL_SYSCONFDIR=\$D/etc
export OMPI_MCA_mca_base_component_path=\$D/openmpi3 OMPI_MCA_mca_base_component_show_load_errors=0
export OMPI_MCA_pml=ob1 OMPI_MCA_btl=self,vader OMPI_MCA_osc=^ucx OMPI_MCA_plm_rsh_agent=false
export PMIX_MCA_mca_base_component_path=\$D/pmix PMIX_MCA_mca_base_component_show_load_errors=0
export PMIX_INSTALL_PREFIX=\$D HWLOC_PLUGINS_PATH=\$D/hwloc
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
EOF
mkdir -p "$(dirname "$out")"
tar -C "$b" -cJf "$out" .
echo "portable_bundle.sh: wrote $out ($(du -h "$out" | cut -f1); unpack to $dest on the target)"
