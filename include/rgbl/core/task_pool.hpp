#pragma once
// A small fixed pool of threads for the per-frame work that splits into independent parts (the depth
// source's preparation beside extraction, pyramid levels, the next frame while this one is tracked).
// A thread that waits for work helps run queued work instead of sleeping, so nested parallelism
// (a task that itself runs parallel_for) cannot deadlock and no core idles while work is queued.
// Results never depend on the thread count: callers write each part's result to its own slot.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace rgbl {

class TaskPool {
  struct State;

 public:
  // A submitted job; wait() runs queued jobs (this one included) until it is done and rethrows what
  // it threw. Destroying a Task waits for its job (whose captures may live on the caller's stack,
  // e.g. during unwinding) and drops its exception.
  class Task {
   public:
    Task() = default;
    Task(Task&& other) noexcept : pool_(other.pool_), state_(std::move(other.state_)) {}
    Task& operator=(Task&& other) noexcept {
      if (this != &other) {
        finish();
        pool_ = other.pool_;
        state_ = std::move(other.state_);
      }
      return *this;
    }
    Task(const Task&) = delete;
    Task& operator=(const Task&) = delete;
    ~Task() { finish(); }
    void wait();
    bool valid() const { return state_ != nullptr; }

   private:
    friend class TaskPool;
    Task(TaskPool* pool, std::shared_ptr<State> state) : pool_(pool), state_(std::move(state)) {}
    void finish() noexcept;
    TaskPool* pool_ = nullptr;
    std::shared_ptr<State> state_;
  };

  // `threads` in all, the callers of wait() and parallel_for() included: threads - 1 workers.
  // 0 = the machine's hardware threads. 1 = no worker: jobs run inside wait(), in submission order.
  explicit TaskPool(int threads = 0);
  ~TaskPool();
  TaskPool(const TaskPool&) = delete;
  TaskPool& operator=(const TaskPool&) = delete;

  int threads() const { return threads_; }

  Task submit(std::function<void()> job);

  // fn(0) ... fn(n - 1), on the workers and the calling thread; returns when all are done and then
  // rethrows the exception of the lowest index that threw.
  void parallel_for(std::size_t n, const std::function<void(std::size_t)>& fn);

  // The machine's hardware threads (at least 1).
  static int hardware_threads();

 private:
  struct State {
    std::function<void()> job;
    bool done = false;
    std::exception_ptr error;
  };
  // Runs one queued job if there is one; false when the queue is empty.
  bool run_one(std::unique_lock<std::mutex>& lock);
  void wait_for(const std::shared_ptr<State>& state);
  void work();

  int threads_ = 1;
  std::mutex mutex_;
  std::condition_variable changed_;  // a job queued or finished, or the pool stopping
  std::deque<std::shared_ptr<State>> queue_;
  bool stop_ = false;
  std::vector<std::thread> workers_;
};

// fn(0) ... fn(n - 1) on `pool`, or in order on the calling thread without one (nullptr): for callers
// whose pool is optional.
void parallel_for(TaskPool* pool, std::size_t n, const std::function<void(std::size_t)>& fn);

}  // namespace rgbl
