#pragma once
// What `rgbl eval` does: an estimated trajectory file against a ground-truth file (KITTI rows or TUM
// timestamps), every metric, and its reports (text and JSON).

#include "rgbl/eval/trajectory_metrics.hpp"

#include <cstddef>
#include <filesystem>
#include <istream>
#include <string>
#include <vector>

namespace rgbl {

struct CompareOptions {
  std::string format = "auto";       // auto (12 fields per row: kitti, 8: tum), kitti or tum
  std::vector<double> lengths;       // KITTI segment lengths, m; empty: kitti_options_for_path
  std::size_t step = 10;             // frames between segment starts
  double max_time_difference = 0.02; // s, TUM: pairing poses by timestamp

  void validate() const;  // throws ConfigError naming the option
};

struct TrajectoryComparison {
  std::filesystem::path estimate, ground_truth;
  std::string format;               // kitti or tum
  std::size_t estimated_poses = 0;  // in the estimate's file
  std::vector<std::string> notes;   // pairing and length choices, for the user
  TrajectoryEvaluation evaluation;  // over the paired poses
};

// "kitti" or "tum" from the first data row. Throws ParseError naming the file and line.
std::string detect_trajectory_format(const std::filesystem::path& file);
// The same from a stream already open (a pipe can be read only once); `file` names it in errors.
std::string detect_trajectory_format(std::istream& in, const std::filesystem::path& file);

// Reads both files (each once: a pipe or a FIFO works) and pairs them: KITTI by row (the ground truth may be longer), TUM by timestamp.
// Throws ParseError / Error naming the files for mixed formats, a shorter ground truth, or fewer than
// 2 pairs.
TrajectoryComparison compare_trajectory_files(const std::filesystem::path& estimate,
                                              const std::filesystem::path& ground_truth,
                                              const CompareOptions& options = {});

// The comparison as JSON (kitti per length, ATE, RPE, drift; NaN as null).
std::string comparison_json(const TrajectoryComparison& comparison);

// The comparison for people, as `rgbl eval` prints it: the files, the notes, the KITTI metric per
// segment length, ATE, RPE and end-point drift ("-" for a length no segment fits).
std::string comparison_text(const TrajectoryComparison& comparison);

}  // namespace rgbl
