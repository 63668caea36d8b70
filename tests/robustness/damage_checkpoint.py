#!/usr/bin/env python3
"""damage_checkpoint.py SRC DST MODE DATASET [ARG]: a copy of checkpoint SRC with one fault.

  flip DATASET K     flip one bit of byte K of the dataset's stored data (raw file write, as a
                     disk or a copy would damage it; the dataset's Fletcher32 checksum no longer
                     matches)
  set DATASET EXPR   rewrite the dataset through h5py (a valid checksum) with the values EXPR
                     makes of the array `a` (numpy as np), e.g. "a[3] = a[4]": a file that is
                     intact as HDF5 but impossible as a state (the restore's semantic checks)
  attr OBJECT NAME EXPR  set attribute NAME of OBJECT ("/" for the file) to the value of EXPR
                     (numpy as np), e.g. "np.int64(-5)", "np.float64('nan')", "np.bytes_(b'[' * 9)"
                     (a fixed-length string, as coloc writes them)
"""
import shutil
import sys

import h5py
import numpy as np

src, dst, mode, ds = sys.argv[1:5]
shutil.copy(src, dst)
if mode == "flip":
    k = int(sys.argv[5])
    with h5py.File(dst, "r") as f:
        d = f[ds]
        off = d.id.get_chunk_info(0).byte_offset if d.chunks else d.id.get_offset()
        k = min(k, d.id.get_storage_size() - 5)  # inside the data, before the checksum
    with open(dst, "r+b") as g:
        g.seek(off + k)
        b = g.read(1)
        g.seek(off + k)
        g.write(bytes([b[0] ^ 0x10]))
    print(f"{dst}: flipped a bit of byte {k} of {ds} (file offset {off + k})")
elif mode == "set":
    with h5py.File(dst, "r+") as f:
        a = f[ds][...]
        exec(sys.argv[5], {"np": np, "a": a})
        f[ds][...] = a
    print(f"{dst}: {ds}: {sys.argv[5]}")
elif mode == "attr":
    with h5py.File(dst, "r+") as f:
        f[ds].attrs[sys.argv[5]] = eval(sys.argv[6], {"np": np})
    print(f"{dst}: {ds} attribute {sys.argv[5]} = {sys.argv[6][:60]}")
else:
    sys.exit(f"unknown mode {mode}")
