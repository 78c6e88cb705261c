#include "libnetsim/sweep/sweep_mpi.h"

#include <cstdlib>
#include <stdexcept>

#ifdef NETLAB_HAVE_MPI
#include <mpi.h>
#endif

namespace netlab::netsim {

bool MpiSession::BuiltIn() {
#ifdef NETLAB_HAVE_MPI
  return true;
#else
  return false;
#endif
}

bool MpiSession::Launched() {
  return std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr || std::getenv("PMI_SIZE") != nullptr ||
         std::getenv("PMIX_RANK") != nullptr;
}

#ifdef NETLAB_HAVE_MPI

MpiSession::MpiSession() {
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

MpiSession::~MpiSession() { MPI_Finalize(); }

void MpiSession::Send(int to, int tag, const std::string& bytes) const {
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD);
}

bool MpiSession::Poll(int* from, int* tag, std::string* bytes) const {
  int flag = 0;
  MPI_Status status;
  MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status);
  if (!flag) return false;
  int count = 0;
  MPI_Get_count(&status, MPI_BYTE, &count);
  bytes->resize(count);
  MPI_Recv(bytes->data(), count, MPI_BYTE, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD,
           MPI_STATUS_IGNORE);
  *from = status.MPI_SOURCE;
  *tag = status.MPI_TAG;
  return true;
}

void MpiSession::Abort(int status) const {
  MPI_Abort(MPI_COMM_WORLD, status);
  std::exit(status);
}

#else

MpiSession::MpiSession() {
  throw std::runtime_error(
      "this netlab was built without MPI (install libopenmpi-dev and rebuild to run under "
      "mpirun)");
}
MpiSession::~MpiSession() = default;
void MpiSession::Send(int, int, const std::string&) const {}
bool MpiSession::Poll(int*, int*, std::string*) const { return false; }
void MpiSession::Abort(int status) const { std::exit(status); }

#endif

}  // namespace netlab::netsim
