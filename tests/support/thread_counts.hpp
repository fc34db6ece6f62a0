#pragma once
// Runs a pipeline with one frame thread and with each of `counts`, and checks that every frame's
// pose, state, inliers and keyframe decision are the same to the bit (tests/pipeline, and the TSan
// executable in tests/reliability).

#include "rgbl/pipeline/pipeline.hpp"

#include <catch2/catch.hpp>

#include <cstddef>
#include <initializer_list>

namespace rgbl::test {

inline void check_thread_counts_agree(PipelineOptions o, std::initializer_list<int> counts) {
  o.threads = 1;
  const RunResult serial = Pipeline(o).run();
  CHECK(serial.threads == 1);
  REQUIRE(serial.frames.size() >= 10);
  for (const int threads : counts) {
    o.threads = threads;
    const RunResult run = Pipeline(o).run();
    CHECK(run.threads == threads);
    REQUIRE(run.frames.size() == serial.frames.size());
    for (std::size_t i = 0; i < serial.frames.size(); ++i) {
      const auto& a = serial.frames[i].result;
      const auto& b = run.frames[i].result;
      INFO("frame " << a.frame_index << ", " << threads << " threads");
      CHECK(b.state == a.state);
      CHECK(b.inliers == a.inliers);
      CHECK(b.keypoints_with_depth == a.keypoints_with_depth);
      CHECK(b.keyframe == a.keyframe);
      CHECK(run.trajectory.poses[i].matrix() == serial.trajectory.poses[i].matrix());
    }
    CHECK(run.landmarks.size() == serial.landmarks.size());
    // the frame's critical path shrinks, its stages do not vanish
    CHECK(run.timings().front.median > 0.0);
    CHECK(run.timings().extraction.median > 0.0);
  }
}

}  // namespace rgbl::test
