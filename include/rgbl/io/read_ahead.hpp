#pragma once
// Loads the next frames of a sequence on a second thread while the caller processes the current one.

#include "rgbl/io/frame_input.hpp"
#include "rgbl/io/sequence.hpp"

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

namespace rgbl {

struct ReadAheadOptions {
  std::size_t depth = 3;  // frames loaded ahead of the one the caller holds (queue bound), >= 1
  std::size_t first = 0;  // first frame index
  std::size_t count = 0;  // frames to deliver; 0 = up to the end of the sequence
  std::size_t step = 1;   // deliver every step-th frame (first, first + step, ...), >= 1
  LoadOptions load{};     // what each frame loads (a KITTI frame's unused images are most of its load time)

  void validate() const;
};

// next() returns frames first, first+step, ... in order and nullopt after the last one. A frame whose
// load threw rethrows that exception from next() when its turn comes (earlier frames are delivered
// first), and nothing is loaded after it. The destructor stops the loader and joins it, also when
// the caller leaves early. The sequence must outlive this object.
class ReadAhead {
 public:
  explicit ReadAhead(const Sequence& sequence, const ReadAheadOptions& options = {});
  ~ReadAhead();
  ReadAhead(const ReadAhead&) = delete;
  ReadAhead& operator=(const ReadAhead&) = delete;

  std::optional<FrameInput> next();

 private:
  struct Slot {
    std::optional<FrameInput> frame;
    std::exception_ptr error;
  };
  void run();

  const Sequence& sequence_;
  std::size_t depth_;
  std::size_t first_;
  std::size_t step_;
  std::size_t end_;
  LoadOptions load_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Slot> queue_;
  bool stop_ = false;
  bool finished_ = false;  // loader has pushed its last slot
  std::thread thread_;     // last: starts after everything above is initialised
};

}  // namespace rgbl
