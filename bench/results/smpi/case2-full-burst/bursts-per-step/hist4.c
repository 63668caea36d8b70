// hist4.c — burst time series for SMPI runs (issue 26; run.sh builds and preloads it after
// libcoloc_smpi_burst.so): every burst (raw elapsed, corrected by COLOC_SMPI_BURST_OFFSET) goes
// to the slot of the simulated clock (HIST_SLOT seconds, default 1 ms; analyse4.py assumes 1 ms)
// at which SMPI charges it, by size class. A value over 1 s is SimGrid's own wall timer, not a
// burst, and is left out.
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
typedef double (*elapsed_fn)(const void*);
double simgrid_get_clock(void);
static elapsed_fn real_elapsed;
enum { kSlots = 40000 };
static long cnt[kSlots][3];
static double chg[kSlots][3];
static double off = -1, slot = 1e-3;
static int odd, last = -1;
double xbt_os_timer_elapsed(const void* t) {
  if (!real_elapsed) real_elapsed = (elapsed_fn)dlsym(RTLD_NEXT, "xbt_os_timer_elapsed");
  if (off < 0) {
    const char* o = getenv("COLOC_SMPI_BURST_OFFSET");
    off = o ? atof(o) : 0;
    const char* s = getenv("HIST_SLOT");
    if (s) slot = atof(s);
  }
  double e = real_elapsed(t);
  if (e > 1.0) return e;  // SimGrid's own wall timer
  if ((odd ^= 1)) {
    int k = (int)(simgrid_get_clock() / slot);
    if (k < 0) k = 0;
    if (k >= kSlots) k = kSlots - 1;
    int c = e < 10e-6 ? 0 : e < 1e-3 ? 1 : 2;
    double v = e - off > 0 ? e - off : 0;
    cnt[k][c]++;
    chg[k][c] += v;
    if (k > last) last = k;
  }
  return e;
}
__attribute__((destructor)) static void dump(void) {
  if (last < 0) return;
  FILE* f = fopen(getenv("HIST_OUT"), "w");
  fprintf(f,
          "# slot_start_s n_lt10us s_lt10us n_10us_1ms s_10us_1ms n_gt1ms s_gt1ms (offset %.3g)\n",
          off);
  for (int k = 0; k <= last; ++k)
    if (cnt[k][0] + cnt[k][1] + cnt[k][2])
      fprintf(f, "%.4f %ld %.6f %ld %.6f %ld %.6f\n", k * slot, cnt[k][0], chg[k][0], cnt[k][1],
              chg[k][1], cnt[k][2], chg[k][2]);
  fclose(f);
}
