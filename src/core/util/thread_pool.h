// A fixed set of worker threads that run one job at a time: job(i) for every i in [0, n), handed
// out one index at a time, the calling thread working too. The caster keeps one for as long as it
// lives, so a scan does not start threads.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace laser_raycast {
namespace core {

// A thread count as the settings give it (CastConfig::threads, BvhConfig::threads): 0 means every
// core the machine reports (at least 1).
int threadsFor(int setting);

class ThreadPool {
 public:
  // threads: how many threads run a job, the caller included (>= 1).
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }

  // Runs job(i) for i in [0, n) on the pool's threads and returns when all are done. If a call
  // throws, the first exception is rethrown here once the others have finished.
  void run(int n, const std::function<void(int)>& job);

 private:
  void work();
  void drain();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(int)>* job_ = nullptr;
  int count_ = 0;
  std::atomic<int> next_{0};
  int busy_ = 0;                  // workers still in the current job
  std::uint64_t generation_ = 0;  // which job the workers last joined
  bool stop_ = false;
  std::exception_ptr error_;
};

}  // namespace core
}  // namespace laser_raycast
