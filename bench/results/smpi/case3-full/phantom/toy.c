#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
static double work[4096];
int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int r, P; MPI_Comm_rank(MPI_COMM_WORLD, &r); MPI_Comm_size(MPI_COMM_WORLD, &P);
  int iters = atoi(argv[1]), n = atoi(argv[2]);
  double s = 0, x = 1.0, y;
  double t0 = MPI_Wtime();
  for (int it = 0; it < iters; ++it) {
    for (int i = 0; i < n; ++i) { work[i & 4095] += 1e-9 * i; s += work[i & 4095]; }
    MPI_Sendrecv(&x, 1, MPI_DOUBLE, (r + 1) % P, 0, &y, 1, MPI_DOUBLE, (r + P - 1) % P, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  }
  double t = MPI_Wtime() - t0, tmax;
  MPI_Reduce(&t, &tmax, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
  if (r == 0) printf("P %d iters %d n %d: %.6f s, %.3f us/iter (s=%g)\n", P, iters, n, tmax, 1e6 * tmax / iters, s);
  MPI_Finalize();
  return 0;
}
