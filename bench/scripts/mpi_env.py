"""The environment the benchmark scripts give mpirun: Open MPI as root, more ranks than cores,
waiting ranks yielding their core (several ranks may share one) and no CMA single-copy (blocked
in containers). A value already set in the environment is kept for the last two."""
import os


def mpi_env():
    return dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                OMPI_MCA_rmaps_base_oversubscribe="1",
                OMPI_MCA_mpi_yield_when_idle=os.environ.get("OMPI_MCA_mpi_yield_when_idle", "1"),
                OMPI_MCA_btl_vader_single_copy_mechanism=os.environ.get(
                    "OMPI_MCA_btl_vader_single_copy_mechanism", "none"))
