// Worker threads kept from one parallel_for to the next (see parallel.hpp).
//
// A parallel_for used to start and join its own threads: ~40 us per call on the project VM, a
// dozen calls per run (live mode: per update), and every new thread allocated its thread_local
// scratch (the family cuts' heights and buckets, the loop assembly's tables) anew. The pool's
// threads wait on a condition variable between calls and keep their scratch.
#ifdef _WIN32
#include <process.h>
#define OSTEON_GETPID _getpid
using pid_t = int;
#else
#include <unistd.h>
#define OSTEON_GETPID getpid
#endif

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>

#include "parallel.hpp"

namespace osteon::detail {
namespace {

class WorkerPool {
 public:
  pid_t pid() const { return pid_; }

  // See pool_run.
  bool run(int workers, const std::function<void(int)>& body) {
    std::unique_lock<std::mutex> busy(busy_, std::try_to_lock);
    if (!busy.owns_lock()) return false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (; threads_ < workers - 1; ++threads_)
        std::thread(&WorkerPool::loop, this, threads_ + 1, generation_).detach();
      body_ = &body;
      active_ = workers;
      remaining_ = workers - 1;
      ++generation_;
    }
    wake_.notify_all();
    body(0);
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return remaining_ == 0; });
    body_ = nullptr;
    return true;
  }

 private:
  // Worker `id` (1, 2, ...): runs the body of each call that asks for more than id workers.
  void loop(int id, std::uint64_t seen) {
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
      wake_.wait(lock, [&] { return generation_ != seen; });
      seen = generation_;
      if (id >= active_) continue;
      const std::function<void(int)>* body = body_;
      lock.unlock();
      (*body)(id);  // never throws: parallel_for's body keeps the first error
      lock.lock();
      if (--remaining_ == 0) done_.notify_one();
    }
  }

  const pid_t pid_ = OSTEON_GETPID();
  std::mutex busy_;   // held by the call using the pool
  std::mutex mutex_;  // guards the members below
  std::condition_variable wake_, done_;
  int threads_ = 0;  // pool threads started (workers 1 .. threads_)
  std::uint64_t generation_ = 0;
  int active_ = 0;     // workers of the current call
  int remaining_ = 0;  // pool workers of the current call not done yet
  const std::function<void(int)>* body_ = nullptr;
};

}  // namespace

bool pool_run(int workers, const std::function<void(int)>& body) {
  static std::mutex guard;
  static WorkerPool* pool = nullptr;
  WorkerPool* current = nullptr;
  {
    std::lock_guard<std::mutex> lock(guard);
    // A forked child has none of its parent's threads: it starts a pool of its own (the
    // parent's object is left as it is, never freed; so are the pool's threads at exit).
    if (pool == nullptr || pool->pid() != OSTEON_GETPID()) pool = new WorkerPool();
    current = pool;
  }
  return current->run(workers, body);
}

}  // namespace osteon::detail
