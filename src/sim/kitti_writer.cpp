// Writing a synthetic sequence in KITTI odometry layout.
#include "rgbl/core/error.hpp"
#include "rgbl/io/image.hpp"
#include "rgbl/sim/synthetic.hpp"

#include <fmt/format.h>
#include <fmt/os.h>

#include <cmath>
#include <fstream>
#include <system_error>

namespace rgbl {
namespace {

class SequenceWriter {
 public:
  SequenceWriter(const std::filesystem::path& root, int sequence, const SyntheticOptions& options,
                 const KittiCalibration& calibration)
      : layout_(kitti_layout(root, sequence)) {
    // never over another sequence: its images, scans and ground truth would be replaced file by file
    for (const auto& existing : {layout_.sequence_dir, layout_.poses_file}) {
      std::error_code ec;
      if (std::filesystem::exists(std::filesystem::symlink_status(existing, ec))) {
        throw Error(fmt::format("{}: exists; a synthetic sequence is written only where it replaces nothing "
                                "(choose a new or empty folder, or another sequence number)",
                                existing.string()));
      }
    }
    // only the folders of what is rendered: the KITTI loader takes a camera folder as the camera's presence
    for (std::size_t c = 0; c < 4; ++c) {
      if (options.cameras[c]) std::filesystem::create_directories(layout_.sequence_dir / fmt::format("image_{}", c));
    }
    std::filesystem::create_directories(layout_.sequence_dir / "velodyne");
    if (options.render_depth) std::filesystem::create_directories(layout_.sequence_dir / "depth");
    std::filesystem::create_directories(layout_.poses_file.parent_path());
    write_calibration(calibration);
    write_options(options);
    times_.open(layout_.sequence_dir / "times.txt");
    poses_.open(layout_.poses_file);
    if (!times_) throw Error(fmt::format("cannot write {}", (layout_.sequence_dir / "times.txt").string()));
    if (!poses_) throw Error(fmt::format("cannot write {}", layout_.poses_file.string()));
  }

  void add(const SyntheticFrame& f) {
    const std::string name = fmt::format("{:06d}", f.index);
    for (int c = 0; c < 4; ++c) {
      const cv::Mat& image = f.images[static_cast<std::size_t>(c)];
      if (!image.empty()) write_png_file(layout_.sequence_dir / fmt::format("image_{}", c) / (name + ".png"), image);
    }
    if (!f.depth.empty()) write_png_file(layout_.sequence_dir / "depth" / (name + ".png"), encode_depth16(f.depth));
    const auto bin = layout_.sequence_dir / "velodyne" / (name + ".bin");
    std::ofstream out(bin, std::ios::binary);
    if (!f.scan.empty()) {  // a dropped scan is an empty file
      out.write(reinterpret_cast<const char*>(f.scan.data()),
                static_cast<std::streamsize>(f.scan.size() * sizeof(LidarPoint)));
    }
    if (!out) throw Error(fmt::format("cannot write {}", bin.string()));
    times_ << fmt::format("{:.6e}\n", f.timestamp);
    const Matrix34d T = to_3x4(f.T_world_cam0);
    poses_ << row(T) << '\n';
  }

  void finish() {
    times_.close();
    poses_.close();
    if (!times_ || !poses_) throw Error(fmt::format("cannot finish writing {}", layout_.root.string()));
  }

  const KittiLayout& layout() const { return layout_; }

 private:
  static std::string row(const Matrix34d& M) {
    std::string s;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) s += fmt::format("{}{:.12e}", s.empty() ? "" : " ", M(r, c) + 0.0);  // no "-0"
    return s;
  }

  void write_calibration(const KittiCalibration& calibration) const {
    const auto file = layout_.sequence_dir / "calib.txt";
    std::ofstream out(file);
    for (int i = 0; i < 4; ++i) out << fmt::format("P{}: {}\n", i, row(calibration.P[static_cast<std::size_t>(i)]));
    out << "Tr: " << row(to_3x4(calibration.T_cam0_lidar)) << '\n';
    if (!out) throw Error(fmt::format("cannot write {}", file.string()));
  }

  void write_options(const SyntheticOptions& o) const {
    const auto file = layout_.sequence_dir / "sim.txt";
    std::ofstream out(file);
    out << "# rgbl synthetic street (rgbl_sim); depth/ holds camera " << o.depth_camera << "'s exact depth\n";
    if (!o.scenario.empty()) out << fmt::format("scenario: {}\n", o.scenario);
    out << fmt::format("seed: {}\nframes: {}\npath: {}\nspeed: {}\nframe_period: {}\nwidth: {}\nheight: {}\n", o.seed,
                       o.frames, to_string(o.path.kind), o.speed, o.frame_period, o.width, o.height);
    out << fmt::format("image_noise_sigma: {}\ndepth_camera: {}\nlidar_range_noise_sigma: {}\nlidar_dropout: {}\n",
                       o.image_noise_sigma, o.depth_camera, o.lidar.range_noise_sigma, o.lidar.dropout);
    if (o.lidar.elevation_offset_deg != 0.0 || o.lidar.beam_elevation_sigma_deg != 0.0) {
      out << fmt::format("lidar_elevation_offset_deg: {}\nlidar_beam_elevation_sigma_deg: {}\n", o.lidar.elevation_offset_deg,
                         o.lidar.beam_elevation_sigma_deg);
    }
    if (!o.speed_phases.empty()) {
      out << "speed_phases:";
      for (const SpeedPhase& p : o.speed_phases) out << fmt::format(" {}s@{}m/s2", p.duration, p.acceleration);
      out << '\n';
    }
    if (!o.actors.empty()) out << fmt::format("actors: {}\n", o.actors.size());
    if (o.light.cast_shadows) out << "cast_shadows: true\n";
    if (o.exposure_time > 0.0) out << fmt::format("exposure_time: {}\n", o.exposure_time);
    if (!o.exposure_steps.empty() || o.exposure_drift > 0.0) {
      out << "exposure_gain:";
      for (const ExposureStep& e : o.exposure_steps) out << fmt::format(" x{} from frame {};", e.gain, e.frame);
      out << fmt::format(" drift {} over {} frames\n", o.exposure_drift, o.exposure_drift_period);
    }
    if (o.untextured) out << fmt::format("untextured: {} {}\n", o.untextured->first, o.untextured->last);
    if (!o.dropped_scans.empty()) out << fmt::format("dropped_scans: {}\n", fmt::join(o.dropped_scans, " "));
    if (!out) throw Error(fmt::format("cannot write {}", file.string()));
  }

  KittiLayout layout_;
  std::ofstream times_, poses_;
};

}  // namespace

KittiLayout kitti_layout(const std::filesystem::path& root, int sequence) {
  require(sequence >= 0 && sequence <= 99, "sequence", "a sequence number 0..99");
  KittiLayout l;
  l.root = root;
  l.sequence_dir = root / "sequences" / fmt::format("{:02d}", sequence);
  l.poses_file = root / "poses" / fmt::format("{:02d}.txt", sequence);
  return l;
}

KittiLayout write_kitti(const SyntheticGenerator& generator, const std::filesystem::path& root, int sequence,
                        const std::function<void(int)>& on_frame) {
  SequenceWriter writer(root, sequence, generator.options(), generator.calibration());
  for (int i = 0; i < generator.frame_count(); ++i) {
    writer.add(generator.render(i));
    if (on_frame) on_frame(i);
  }
  writer.finish();
  return writer.layout();
}

KittiLayout write_kitti(const SyntheticSequence& sequence, const std::filesystem::path& root, int sequence_number) {
  SequenceWriter writer(root, sequence_number, sequence.options, sequence.calibration);
  for (const auto& f : sequence.frames) writer.add(f);
  writer.finish();
  return writer.layout();
}

}  // namespace rgbl
