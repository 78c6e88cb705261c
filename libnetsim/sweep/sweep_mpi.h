#pragma once
// The MPI ranks of `mpirun -np N netlab sweep ...` (Debian's OpenMPI; an optional build
// dependency: without it netlab builds, MpiSession::BuiltIn() is false and a session cannot be
// made). A session is MPI_Init .. MPI_Finalize, one per process, made only when the process was
// launched by mpirun; it carries byte messages between ranks on MPI_COMM_WORLD, always from the
// thread that made it (MPI_THREAD_FUNNELED is all it asks for).

#include <string>

namespace netlab::netsim {

class MpiSession {
 public:
  // Whether this netlab was built with MPI.
  static bool BuiltIn();
  // Whether the environment is that of a rank started by mpirun / mpiexec (OpenMPI's
  // OMPI_COMM_WORLD_SIZE, or PMI_SIZE / PMIX_RANK of other launchers).
  static bool Launched();

  // MPI_Init. std::runtime_error when netlab is built without MPI.
  MpiSession();
  ~MpiSession();  // MPI_Finalize
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }

  // Sends `bytes` to rank `to` with `tag` (blocking until the buffer can be reused).
  void Send(int to, int tag, const std::string& bytes) const;
  // Receives a message waiting from any rank, any tag: false (and nothing changed) when none is.
  bool Poll(int* from, int* tag, std::string* bytes) const;
  // Ends every rank (MPI_Abort) after a fatal error on one: the others would wait forever.
  [[noreturn]] void Abort(int status) const;

 private:
  int rank_ = 0;
  int size_ = 1;
};

}  // namespace netlab::netsim
