#include "rgbl/io/read_ahead.hpp"

#include "rgbl/core/error.hpp"

#include <algorithm>

namespace rgbl {

void ReadAheadOptions::validate() const {
  require(depth >= 1, "read_ahead.depth", "at least 1 frame");
  require(step >= 1, "read_ahead.step", "at least 1 (every frame)");
}

ReadAhead::ReadAhead(const Sequence& sequence, const ReadAheadOptions& options)
    : sequence_(sequence), depth_(options.depth), first_(std::min(options.first, sequence.size())),
      step_(options.step), load_(options.load) {
  options.validate();
  const std::size_t available = (sequence.size() - first_ + step_ - 1) / step_;  // frames on the stride
  const std::size_t count = options.count == 0 ? available : std::min(options.count, available);
  end_ = count == 0 ? first_ : first_ + (count - 1) * step_ + 1;
  thread_ = std::thread([this] { run(); });
}

ReadAhead::~ReadAhead() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ReadAhead::run() {
  for (std::size_t i = first_; i < end_; i += step_) {
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [this] { return stop_ || queue_.size() < depth_; });
      if (stop_) break;
    }
    Slot slot;
    try {
      slot.frame = sequence_.load(i, load_);
    } catch (...) {
      slot.error = std::current_exception();
    }
    const bool failed = slot.error != nullptr;
    {
      std::lock_guard lock(mutex_);
      queue_.push_back(std::move(slot));
    }
    changed_.notify_all();
    if (failed) break;
  }
  {
    std::lock_guard lock(mutex_);
    finished_ = true;
  }
  changed_.notify_all();
}

std::optional<FrameInput> ReadAhead::next() {
  Slot slot;
  {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [this] { return !queue_.empty() || finished_; });
    if (queue_.empty()) return std::nullopt;
    slot = std::move(queue_.front());
    queue_.pop_front();
  }
  changed_.notify_all();
  if (slot.error) std::rethrow_exception(slot.error);
  return std::move(slot.frame);
}

}  // namespace rgbl
