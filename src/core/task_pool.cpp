#include "rgbl/core/task_pool.hpp"

#include <algorithm>

namespace rgbl {

int TaskPool::hardware_threads() { return std::max(1, static_cast<int>(std::thread::hardware_concurrency())); }

TaskPool::TaskPool(int threads) : threads_(threads > 0 ? threads : hardware_threads()) {
  workers_.reserve(static_cast<std::size_t>(threads_ - 1));
  for (int i = 1; i < threads_; ++i) workers_.emplace_back([this] { work(); });
}

TaskPool::~TaskPool() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  for (auto& w : workers_) w.join();
  // jobs nobody waited for still run (their captures may expect it)
  std::unique_lock lock(mutex_);
  while (run_one(lock)) {
  }
}

bool TaskPool::run_one(std::unique_lock<std::mutex>& lock) {
  if (queue_.empty()) return false;
  std::shared_ptr<State> state = std::move(queue_.front());
  queue_.pop_front();
  lock.unlock();
  try {
    state->job();
  } catch (...) {
    state->error = std::current_exception();
  }
  state->job = nullptr;  // release captures outside the lock
  lock.lock();
  state->done = true;
  changed_.notify_all();
  return true;
}

void TaskPool::work() {
  std::unique_lock lock(mutex_);
  for (;;) {
    if (run_one(lock)) continue;
    if (stop_) return;
    changed_.wait(lock);
  }
}

void TaskPool::wait_for(const std::shared_ptr<State>& state) {
  std::unique_lock lock(mutex_);
  while (!state->done) {
    if (!run_one(lock)) changed_.wait(lock, [&] { return state->done || !queue_.empty(); });
  }
}

TaskPool::Task TaskPool::submit(std::function<void()> job) {
  auto state = std::make_shared<State>();
  state->job = std::move(job);
  {
    std::lock_guard lock(mutex_);
    queue_.push_back(state);
  }
  changed_.notify_one();
  return Task(this, std::move(state));
}

void TaskPool::Task::wait() {
  if (!state_) return;
  pool_->wait_for(state_);
  const std::exception_ptr error = state_->error;
  state_.reset();
  if (error) std::rethrow_exception(error);
}

void TaskPool::Task::finish() noexcept {
  if (!state_) return;
  pool_->wait_for(state_);  // stores, never throws, what the job threw
  state_.reset();
}

void TaskPool::parallel_for(std::size_t n, const std::function<void(std::size_t)>& fn) {
  if (n == 0) return;
  if (threads_ == 1 || n == 1) {
    for (std::size_t i = 0; i < n; ++i) fn(i);
    return;
  }
  // n - 1 jobs queued; the caller runs index 0 itself, then helps with the rest
  std::vector<Task> tasks;
  tasks.reserve(n - 1);
  for (std::size_t i = 1; i < n; ++i) tasks.push_back(submit([&fn, i] { fn(i); }));
  std::exception_ptr first;
  try {
    fn(0);
  } catch (...) {
    first = std::current_exception();
  }
  for (auto& t : tasks) {
    try {
      t.wait();
    } catch (...) {
      if (!first) first = std::current_exception();
    }
  }
  if (first) std::rethrow_exception(first);
}

void parallel_for(TaskPool* pool, std::size_t n, const std::function<void(std::size_t)>& fn) {
  if (pool != nullptr) {
    pool->parallel_for(n, fn);
    return;
  }
  for (std::size_t i = 0; i < n; ++i) fn(i);
}

}  // namespace rgbl
