// Two simulated ranks that each wait for the other's message, which neither sends: SimGrid
// reports the deadlock and smpirun still exits 0; bench/scripts/smpi_run.py must fail
// (test smpi_run_reports_deadlock).
#include <mpi.h>

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, value = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Recv(&value, 1, MPI_INT, 1 - rank, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  MPI_Finalize();
  return 0;
}
