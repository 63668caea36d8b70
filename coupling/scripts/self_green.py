#!/usr/bin/env python3
"""The discrete Green's functions of coupling/src/self_velocity.cpp (docs/coupling.md, "Self-induced
velocity"), for the MAC Stokes operator with the face averages the coupling and the fluid solver
use both ways (symbol cos^2(k_z h/2)); cell-centred force along z, offsets (along, across, across)
in {0, 1}:
  kSelfGreen      steady velocity, units 1/(mu h): periodic N^3 box, mean force removed,
                  Hasimoto's O(h/L) lattice term 2.8373 / (6 pi mu L) added back;
  kGreenBuild     velocity a time t after a constant force was switched on, s = nu t / h^2 on the
                  grid 2^(j/4), j = -24..16 (semi-discrete: continuous time, the fluid's time step
                  is << h^2 / nu); the symbol G(k) (1 - exp(-|k_h|^2 s)) is regular at k = 0, so the
                  lattice sum converges to free space without a lattice term while sqrt(s) << N;
  kSelfPressure   the gradient (irrotational) part of the force, read back as the cell-centred
                  pressure gradient, units 1/h^3 (instantaneous).
Usage: /usr/bin/python3 coupling/scripts/self_green.py 64 128   (needs numpy)"""
import sys
import numpy as np

OFFSETS = [(0, 0, 0), (0, 1, 0), (0, 1, 1), (1, 0, 0), (1, 1, 0), (1, 1, 1)]
SVALS = [2.0 ** (j / 4) for j in range(-24, 17)]


def tables(n):
    k = 2 * np.pi * np.fft.fftfreq(n)
    kx, ky, kz = np.meshgrid(k, k, k, indexing="ij")  # z: the force axis
    s2 = sum((2 * np.sin(q / 2)) ** 2 for q in (kx, ky, kz))
    s2[0, 0, 0] = 1.0
    c2, kz2 = np.cos(kz / 2) ** 2, (2 * np.sin(kz / 2)) ** 2
    g = c2 * (1 - kz2 / s2) / s2
    q = c2 * kz2 / s2
    g[0, 0, 0] = q[0, 0, 0] = 0.0
    cw = [np.cos(kz * a) * np.cos(kx * b) * np.cos(ky * c) for (a, b, c) in OFFSETS]
    steady = [(g * w).mean() + 2.8373 / (6 * np.pi * n) for w in cw]
    pressure = [(q * w).mean() for w in cw]
    build = []
    for s in SVALS:
        gs = -g * np.expm1(-s2 * s)
        build.append([(gs * w).mean() for w in cw])
    return steady, pressure, build


for n in [int(a) for a in sys.argv[1:]] or [128]:
    steady, pressure, build = tables(n)
    print(f"// N = {n}; offsets (along, across, across): " + " ".join(map(str, OFFSETS)))
    print("steady", " ".join(f"{v:.7f}" for v in steady))
    print("pressure", " ".join(f"{v:.7f}" for v in pressure))
    for s, row in zip(SVALS, build):
        print(f"    {{{', '.join(f'{v:.7f}' for v in row)}}},  // s = {s:.6g}")
