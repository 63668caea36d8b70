#!/usr/bin/env python3
"""kSelfGreen (coupling/self_velocity.hpp): the discrete steady Green's function of the MAC Stokes
operator, cell-centred force along z -> cell-centred velocity along z, with the face averages the
coupling and the fluid solver use both ways (symbol cos^2(k_z h/2)). Periodic N^3 boxes, mean force
removed, Hasimoto's O(h/L) lattice term 2.8373 / (6 pi mu L) added back; units 1/(mu h).
Usage: python3 coupling/scripts/self_green.py 32 64 128   (needs numpy; docs/coupling.md)"""
import sys
import numpy as np

def green(n):
    k = 2 * np.pi * np.fft.fftfreq(n)
    kx, ky, kz = np.meshgrid(k, k, k, indexing="ij")
    s2 = sum((2 * np.sin(q / 2)) ** 2 for q in (kx, ky, kz))
    s2[0, 0, 0] = 1.0
    g = np.cos(kz / 2) ** 2 * (1 - (2 * np.sin(kz / 2)) ** 2 / s2) / s2
    g[0, 0, 0] = 0.0
    return np.real(np.fft.ifftn(g)) + 2.8373 / (6 * np.pi * n)

for n in [int(a) for a in sys.argv[1:]] or [64]:
    g = green(n)
    # [along][across][across]: offsets (x, y, z) with z the force axis
    table = [[[g[0, 0, 0], g[1, 0, 0]], [g[0, 1, 0], g[1, 1, 0]]],
             [[g[0, 0, 1], g[1, 0, 1]], [g[0, 1, 1], g[1, 1, 1]]]]
    print(n, np.round(np.array(table), 7).tolist())
