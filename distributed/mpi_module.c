/* libmanibench_mpi.so: the few MPI calls manibench's ranks make, behind a C
 * ABI that the host program dlopens (apps/manibench/mpi_ranks.cpp), so that
 * manibench itself never links libmpi (docs/distributed.md). Every function
 * returns 0 on success or an MPI error code. Messages are byte strings with
 * a tag; sizes past INT_MAX are refused (a trajectory is far below). */
#include <limits.h>
#include <mpi.h>
#include <stdint.h>

#define EXPORT __attribute__((visibility("default")))

EXPORT int manibench_mpi_abi(void) { return 1; }

EXPORT int manibench_mpi_init(int* rank, int* size) {
  int provided = 0;
  int rc = MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, &provided);
  if (rc != MPI_SUCCESS) return rc;
  /* Errors come back as codes, not an abort inside libmpi. */
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  rc = MPI_Comm_rank(MPI_COMM_WORLD, rank);
  if (rc != MPI_SUCCESS) return rc;
  return MPI_Comm_size(MPI_COMM_WORLD, size);
}

EXPORT int manibench_mpi_send(int destination, int tag, const void* data, uint64_t size) {
  if (size > INT_MAX) return MPI_ERR_COUNT;
  return MPI_Send(data, (int)size, MPI_BYTE, destination, tag, MPI_COMM_WORLD);
}

/* Non-blocking: *found is 1 when a message waits (its source, tag, size). */
EXPORT int manibench_mpi_probe(int* found, int* source, int* tag, uint64_t* size) {
  MPI_Status status;
  int rc = MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, found, &status);
  if (rc != MPI_SUCCESS || !*found) return rc;
  int count = 0;
  rc = MPI_Get_count(&status, MPI_BYTE, &count);
  *source = status.MPI_SOURCE;
  *tag = status.MPI_TAG;
  *size = (uint64_t)count;
  return rc;
}

EXPORT int manibench_mpi_receive(int source, int tag, void* data, uint64_t size) {
  if (size > INT_MAX) return MPI_ERR_COUNT;
  return MPI_Recv(data, (int)size, MPI_BYTE, source, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
}

EXPORT int manibench_mpi_finalize(void) { return MPI_Finalize(); }

EXPORT void manibench_mpi_abort(int code) { MPI_Abort(MPI_COMM_WORLD, code); }
