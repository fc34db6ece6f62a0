#include "rgbl/io/settings.hpp"

#include "text.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/geometry/point_cloud.hpp"

#include <fmt/format.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <set>
#include <string_view>
#include <utility>
#include <vector>

namespace rgbl {
namespace {

class Reader {
 public:
  Reader(std::filesystem::path file, cv::FileNode root) : file_(std::move(file)), root_(root) {}

  // The first of `keys` present in the file, or an empty node.
  std::pair<std::string, cv::FileNode> find(std::initializer_list<std::string_view> keys) {
    for (const auto key : keys) {
      const std::string k(key);
      used_.insert(k);
      cv::FileNode node = root_[k];
      if (!node.empty() && !node.isNone()) return {k, node};
    }
    return {std::string(*keys.begin()), cv::FileNode()};
  }

  std::optional<double> number(std::initializer_list<std::string_view> keys) {
    auto [key, node] = find(keys);
    if (node.empty() || node.isNone()) return std::nullopt;
    if (!node.isInt() && !node.isReal()) fail(key, "a number", node);
    const double v = node.isInt() ? static_cast<double>(static_cast<int>(node)) : static_cast<double>(node);
    if (!std::isfinite(v)) fail(key, "a finite number", node);
    return v;
  }

  std::optional<int> integer(std::initializer_list<std::string_view> keys) {
    auto [key, node] = find(keys);
    if (node.empty() || node.isNone()) return std::nullopt;
    if (node.isInt()) return static_cast<int>(node);
    if (node.isReal()) {
      const double v = static_cast<double>(node);
      if (std::isfinite(v) && v == std::round(v) && std::abs(v) < 1e9) return static_cast<int>(v);
    }
    fail(key, "an integer", node);
  }

  std::optional<std::string> string(std::initializer_list<std::string_view> keys) {
    auto [key, node] = find(keys);
    if (node.empty() || node.isNone()) return std::nullopt;
    if (!node.isString()) fail(key, "a string", node);
    return static_cast<std::string>(node);
  }

  [[noreturn]] void fail(const std::string& key, std::string_view expected, const cv::FileNode& node) const {
    throw ParseError(file_, 0, fmt::format("key '{}': expected {}, found {}", key, expected, describe(node)));
  }
  [[noreturn]] void fail(const std::string& key, std::string_view expected) const {
    throw ParseError(file_, 0, fmt::format("key '{}': expected {}", key, expected));
  }

  // Keys of the file that were never asked for.
  std::vector<std::string> unused() const {
    std::vector<std::string> keys;
    for (auto it = root_.begin(); it != root_.end(); ++it) {
      const std::string name = (*it).name();
      if (used_.count(name) != 0 || name.starts_with("Viewer.") || name == "File.version" || name == "Camera.type" ||
          name == "System.SaveAtlasToFile" || name == "System.LoadAtlasFromFile") {
        continue;
      }
      keys.push_back(name);
    }
    return keys;
  }

 private:
  static std::string describe(const cv::FileNode& node) {
    if (node.isString()) return fmt::format("the string '{}'", static_cast<std::string>(node));
    if (node.isSeq()) return "a sequence";
    if (node.isMap()) return "a map";
    if (node.isInt()) return fmt::format("the integer {}", static_cast<int>(node));
    if (node.isReal()) return fmt::format("the number {}", static_cast<double>(node));
    return "something else";
  }

  std::filesystem::path file_;
  cv::FileNode root_;
  std::set<std::string> used_;
};

}  // namespace

void OrbSettings::validate() const {
  require(n_features > 0, "ORBextractor.nFeatures", "a positive number of features");
  require(scale_factor > 1.0, "ORBextractor.scaleFactor", "a scale factor > 1");
  require(n_levels >= 1 && n_levels <= 32, "ORBextractor.nLevels", "1..32 pyramid levels");
  require(ini_th_fast > 0 && ini_th_fast < 256, "ORBextractor.iniThFAST", "a FAST threshold in 1..255");
  require(min_th_fast > 0 && min_th_fast <= ini_th_fast, "ORBextractor.minThFAST", "a FAST threshold in 1..iniThFAST");
  require(!features_per_node || *features_per_node >= 1, "ORBextractor.featuresPerNode", "a count >= 1");
  require(!spread_fraction || (*spread_fraction > 0.0 && *spread_fraction <= 1.0), "ORBextractor.spreadFraction",
          "a fraction in (0, 1]");
}

void LoopClosingSettings::validate() const {
  require(!max_place_distance || (*max_place_distance > 0.0 && *max_place_distance <= 1.0),
          "LoopClosing.MaxPlaceDistance", "a Scan Context distance in (0, 1]");
  require(!consistent_keyframes || *consistent_keyframes >= 1, "LoopClosing.ConsistentKeyframes", "a count >= 1");
  require(!max_drift_percent || *max_drift_percent > 0.0, "LoopClosing.MaxDriftPercent", "a percentage > 0");
  require(!max_drift_deg_per_100m || *max_drift_deg_per_100m > 0.0, "LoopClosing.MaxDriftDegPer100m",
          "degrees per 100 m > 0");
  require(!bridge_max_gap_s || (std::isfinite(*bridge_max_gap_s) && *bridge_max_gap_s > 0.0), "LoopClosing.BridgeMaxGap",
          "seconds > 0");
}

Settings read_settings(const std::filesystem::path& yaml) {
  // OpenCV insists on a "%YAML:1.0" first line; plain YAML files get it added in memory.
  std::string text;
  {
    std::ifstream in = open_input_file(yaml, "an ORB-SLAM style %YAML:1.0 settings file", true);
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  if (text.starts_with("\xEF\xBB\xBF")) text.erase(0, 3);  // UTF-8 byte order mark
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) {
    throw ParseError(yaml, 0, "is empty (expected 'Key: value' settings)");
  }
  // OpenCV 4.6's YAML parser never returns on some malformed input, found by fuzz_settings:
  // - lines starting with "---" ("----s\n----\nL"): a settings file is one document, so a single plain
  //   "---" line is allowed and nothing else;
  // - a key indented less than the first key (" t: 0\nL: -\na"): invalid YAML anyway (the first key
  //   sets the top-level map's indentation), so it is refused with its line.
  // It also recurses once per nesting level and overflows the stack on deep nesting ('[' x 50000):
  // settings are flat, so nesting beyond kMaxNesting levels (flow brackets, indentation and "- " items)
  // is refused with its line. And it keeps the last of two equal keys: each key once per map, at the
  // top level and in nested block maps (e.g. an !!opencv-matrix's rows, cols and data).
  {
    constexpr std::size_t kMaxNesting = 64;
    std::size_t line_no = 0, markers = 0, pos = 0;
    std::optional<std::pair<std::size_t, std::size_t>> first_key;  // (indentation, line)
    std::size_t flow = 0;                 // open '[' and '{' (they may span lines)
    std::vector<std::size_t> indents;     // indentation of the enclosing block levels
    // the block maps open at this line, innermost last: (indentation, key -> line)
    std::vector<std::pair<std::size_t, std::map<std::string, std::size_t>>> maps;
    while (pos < text.size()) {
      const std::size_t end = std::min(text.find('\n', pos), text.size());
      std::string_view line(text.data() + pos, end - pos);
      ++line_no;
      pos = end + 1;
      if (line.starts_with("---")) {
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.remove_suffix(1);
        if (line != "---" || ++markers > 1) {
          throw ParseError(yaml, line_no, "expected 'Key: value' (a settings file is one YAML document; '---' "
                                          "may only start it)");
        }
        continue;
      }
      const std::size_t indent = std::min(line.find_first_not_of(' '), line.size());
      const std::string_view content = line.substr(indent);
      if (content.find_first_not_of(" \t\r") == std::string_view::npos || content.starts_with('#') ||
          (indent == 0 && content.starts_with('%'))) {
        continue;  // blank, comment or directive
      }
      if (!first_key) {
        first_key.emplace(indent, line_no);
      } else if (indent < first_key->first) {
        throw ParseError(yaml, line_no,
                         fmt::format("expected 'Key: value' indented like the first key (line {}, {} spaces), "
                                     "found {} spaces",
                                     first_key->second, first_key->first, indent));
      }
      const bool block_line = flow == 0;  // not inside a flow collection spanning lines
      // block nesting: indentation levels, and "- - x" items nested on one line
      if (flow == 0) {
        while (!indents.empty() && indents.back() >= indent) indents.pop_back();
        indents.push_back(indent);
      }
      std::size_t items = 0;
      for (std::size_t k = 0; k + 1 < content.size() && content[k] == '-' && (content[k + 1] == ' ' || content[k + 1] == '\t');) {
        ++items;
        k = std::min(content.find_first_not_of(" \t", k + 1), content.size());
      }
      // flow nesting, outside quotes and comments
      char quote = 0;
      std::size_t deepest = flow;
      for (std::size_t k = 0; k < content.size(); ++k) {
        const char c = content[k];
        if (quote != 0) {
          if (c == quote) quote = 0;
        } else if (c == '"' || c == '\'') {
          quote = c;
        } else if (c == '#' && (k == 0 || content[k - 1] == ' ' || content[k - 1] == '\t')) {
          break;
        } else if (c == '[' || c == '{') {
          deepest = std::max(deepest, ++flow);
        } else if ((c == ']' || c == '}') && flow > 0) {
          --flow;
        }
      }
      if (indents.size() + items + deepest > kMaxNesting) {
        throw ParseError(yaml, line_no,
                         fmt::format("nested deeper than {} levels (expected flat 'Key: value' settings)", kMaxNesting));
      }
      // a line closes the maps indented deeper (also a new item of a sequence: those of the item before)
      if (block_line) {
        while (!maps.empty() && maps.back().first > indent) maps.pop_back();
      }
      const std::size_t colon = content.find(':');
      const bool quoted_key = content.starts_with('"') || content.starts_with('\'');
      if (block_line && items == 0 && colon != std::string_view::npos && !content.starts_with('[') &&
          !content.starts_with('{') &&
          (colon + 1 == content.size() || content[colon + 1] == ' ' || content[colon + 1] == '\t' ||
           content[colon + 1] == '\r' || quoted_key)) {
        std::string_view key = content.substr(0, colon);
        while (!key.empty() && (key.back() == ' ' || key.back() == '\t')) key.remove_suffix(1);
        if (key.size() >= 2 && (key.front() == '"' || key.front() == '\'') && key.back() == key.front()) {
          key = key.substr(1, key.size() - 2);
        }
        if (maps.empty() || maps.back().first < indent) maps.emplace_back(indent, std::map<std::string, std::size_t>{});
        const auto [it, inserted] = maps.back().second.emplace(std::string(key), line_no);
        if (!inserted) {
          throw ParseError(yaml, line_no,
                           fmt::format("key '{}' given twice (lines {} and {}); expected each key once", key,
                                       it->second, line_no));
        }
      }
    }
  }
  if (!text.starts_with("%YAML")) text = "%YAML:1.0\n" + text;
  cv::FileStorage storage;
  try {
    storage.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    throw ParseError(yaml, 0,
                     fmt::format("not a readable YAML settings file: expected 'Key: value' lines (OpenCV: {})", e.err));
  } catch (const std::exception&) {
    // OpenCV 4.6's parser lets standard exceptions escape on some malformed input (found by
    // fuzz_settings: std::length_error on a map with an empty key, `a: { : { b: 1 "x" }`).
    throw ParseError(yaml, 0, "not a readable YAML settings file: expected 'Key: value' lines (OpenCV's parser failed)");
  }
  if (!storage.isOpened())
    throw ParseError(yaml, 0, "cannot open (expected an ORB-SLAM style %YAML:1.0 settings file)");
  if (!storage.root().isMap()) throw ParseError(yaml, 0, "expected a map of 'Key: value' settings");

  Settings s;
  s.file = yaml;
  Reader r(yaml, storage.root());

  // Camera: fx fy cx cy all or none; "Camera1." is ORB-SLAM3's newer spelling.
  const auto cam_key = [](std::string_view name) {
    return std::array<std::string, 2>{fmt::format("Camera.{}", name), fmt::format("Camera1.{}", name)};
  };
  std::array<std::optional<double>, 4> intrinsics;
  const std::array<std::string_view, 4> names{"fx", "fy", "cx", "cy"};
  for (std::size_t k = 0; k < 4; ++k) {
    const auto keys = cam_key(names[k]);
    intrinsics[k] = r.number({keys[0], keys[1]});
  }
  const auto given = std::count_if(intrinsics.begin(), intrinsics.end(), [](const auto& v) { return v.has_value(); });
  if (given != 0 && given != 4) {
    for (std::size_t k = 0; k < 4; ++k) {
      if (!intrinsics[k]) r.fail(cam_key(names[k])[0], "a number (Camera.fx, fy, cx, cy come together)");
    }
  }
  if (given == 4) {
    PinholeCamera cam;
    cam.fx = *intrinsics[0];
    cam.fy = *intrinsics[1];
    cam.cx = *intrinsics[2];
    cam.cy = *intrinsics[3];
    const auto read_distortion = [&](std::string_view name, double& out) {
      const auto keys = cam_key(name);
      if (const auto v = r.number({keys[0], keys[1]})) out = *v;
    };
    read_distortion("k1", cam.distortion.k1);
    read_distortion("k2", cam.distortion.k2);
    read_distortion("p1", cam.distortion.p1);
    read_distortion("p2", cam.distortion.p2);
    read_distortion("k3", cam.distortion.k3);
    if (const auto w = r.integer({"Camera.width", "Camera1.width"})) cam.width = *w;
    if (const auto h = r.integer({"Camera.height", "Camera1.height"})) cam.height = *h;
    if (!(cam.fx > 0.0 && cam.fy > 0.0)) r.fail("Camera.fx", "positive focal lengths (Camera.fx, Camera.fy)");
    if (cam.width < 0 || cam.height < 0) r.fail("Camera.width", "a non-negative image size");
    if (const auto why = cam.implausibility()) r.fail("Camera.fx", fmt::format("plausible intrinsics: {}", *why));
    s.camera = cam;
  }
  s.fps = r.number({"Camera.fps"});
  s.bf = r.number({"Camera.bf", "Stereo.b"});
  if (const auto rgb = r.integer({"Camera.RGB"})) {
    if (*rgb != 0 && *rgb != 1) r.fail("Camera.RGB", "0 (BGR) or 1 (RGB)");
    s.rgb_order = *rgb == 1;
  }
  s.th_depth = r.number({"ThDepth", "Stereo.ThDepth"});
  s.depth_map_factor = r.number({"DepthMapFactor", "RGBD.DepthMapFactor"});

  if (const auto v = r.integer({"ORBextractor.nFeatures"})) s.orb.n_features = *v;
  if (const auto v = r.number({"ORBextractor.scaleFactor"})) s.orb.scale_factor = *v;
  if (const auto v = r.integer({"ORBextractor.nLevels"})) s.orb.n_levels = *v;
  if (const auto v = r.integer({"ORBextractor.iniThFAST"})) s.orb.ini_th_fast = *v;
  if (const auto v = r.integer({"ORBextractor.minThFAST"})) s.orb.min_th_fast = *v;
  if (const auto v = r.integer({"ORBextractor.featuresPerNode"})) s.orb.features_per_node = *v;
  if (const auto v = r.number({"ORBextractor.spreadFraction"})) s.orb.spread_fraction = *v;

  if (const auto v = r.string({"LiDAR.Method"})) s.lidar_method = *v;
  if (const auto v = r.number({"LiDAR.min_dist"})) s.projection.min_depth = static_cast<float>(*v);
  if (const auto v = r.number({"LiDAR.max_dist"})) s.projection.max_depth = static_cast<float>(*v);
  std::array<std::optional<double>, 12> tr;
  int tr_given = 0;
  for (int k = 0; k < 12; ++k) {
    tr[static_cast<std::size_t>(k)] = r.number({fmt::format("LiDAR.Tr{}{}", k / 4 + 1, k % 4 + 1)});
    tr_given += tr[static_cast<std::size_t>(k)] ? 1 : 0;
  }
  if (tr_given != 0 && tr_given != 12) {
    for (int k = 0; k < 12; ++k) {
      if (!tr[static_cast<std::size_t>(k)]) {
        r.fail(fmt::format("LiDAR.Tr{}{}", k / 4 + 1, k % 4 + 1), "a number (LiDAR.Tr11..LiDAR.Tr34 come together)");
      }
    }
  }
  if (tr_given == 12) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (int k = 0; k < 12; ++k) T.matrix()(k / 4, k % 4) = *tr[static_cast<std::size_t>(k)];
    const Eigen::Matrix3d R = T.linear();
    if ((R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 ||
        std::abs(R.determinant() - 1.0) > 1e-3) {
      r.fail("LiDAR.Tr11", "LiDAR.Tr11..Tr33 to form a rotation matrix");
    }
    s.T_cam_lidar = T;
  }
  if (const auto v = r.string({"LiDAR.MethodInverseDilation.KernelType"})) s.kernel_type = *v;
  if (const auto v = r.integer({"LiDAR.MethodInverseDilation.KernelSize_u"})) {
    if (*v < 1 || *v % 2 == 0) r.fail("LiDAR.MethodInverseDilation.KernelSize_u", "an odd kernel size >= 1");
    s.kernel_size = *v;
  }
  if (const auto v = r.number({"LiDAR.OcclusionWindowDeg"})) {
    if (!(*v >= 0.0 && *v < 5.0)) r.fail("LiDAR.OcclusionWindowDeg", "0 (off) .. 5 deg");
    s.occlusion_window_deg = *v;
  }
  if (const auto v = r.number({"LiDAR.OcclusionRatio"})) {
    if (!(*v > 1.0)) r.fail("LiDAR.OcclusionRatio", "a depth ratio > 1");
    s.occlusion_ratio = *v;
  }
  if (const auto v = r.number({"LiDAR.SurfaceFitWindowDeg"})) {
    if (!(*v >= 0.0 && *v < 5.0)) r.fail("LiDAR.SurfaceFitWindowDeg", "0 (off) .. 5 deg");
    s.surface_fit_window_deg = *v;
  }
  if (const auto v = r.integer({"LiDAR.SurfaceStepPx"})) {
    if (!(*v >= 1 && *v <= 15)) r.fail("LiDAR.SurfaceStepPx", "1 .. 15 px");
    s.surface_step_px = static_cast<int>(*v);
  }
  if (const auto v = r.number({"LiDAR.RegistrationSigmaDeg"})) {
    if (!(*v >= 0.0 && *v < 5.0)) r.fail("LiDAR.RegistrationSigmaDeg", "0 (off) .. 5 deg");
    s.registration_sigma_deg = *v;
  }
  if (const auto v = r.number({"LiDAR.ElevationCorrection"})) {
    if (!(std::abs(*v) <= 2.0)) r.fail("LiDAR.ElevationCorrection", "an angle in deg, -2 .. 2");
    s.elevation_correction_deg = *v;
  }
  if (const auto v = r.number({"LiDAR.TimeOffset"})) {
    if (!(std::abs(*v) <= kMaxScanAge)) r.fail("LiDAR.TimeOffset", kScanAgeExpected);
    s.scan_time_offset = *v;
  }

  const auto flag = [&](std::string_view key) -> std::optional<bool> {
    const auto v = r.integer({key});
    if (!v) return std::nullopt;
    if (*v != 0 && *v != 1) r.fail(std::string(key), "0 (off) or 1 (on)");
    return *v == 1;
  };
  s.kernel_from_ring_spacing = flag("LiDAR.KernelFromRingSpacing");
  s.loop_closing.enabled = flag("LoopClosing.Enabled");
  s.loop_closing.max_place_distance = r.number({"LoopClosing.MaxPlaceDistance"});
  if (const auto v = r.string({"LoopClosing.Places"})) {
    const std::vector<std::string_view> methods = detail::split(*v);
    // one name per comma-separated field: no empty field, no two names in one
    if (methods.empty() || std::cmp_not_equal(std::count(v->begin(), v->end(), ',') + 1, methods.size())) {
      r.fail("LoopClosing.Places", "place recogniser names separated by commas, e.g. \"scan_context,bow\"");
    }
    s.loop_closing.places = std::vector<std::string>(methods.begin(), methods.end());
  }
  if (const auto v = r.string({"LoopClosing.Vocabulary"})) {
    if (v->empty()) r.fail("LoopClosing.Vocabulary", "a vocabulary file (written by `rgbl vocab train`)");
    const std::filesystem::path p = *v;
    s.loop_closing.vocabulary = p.is_absolute() ? p : yaml.parent_path() / p;
  }
  s.loop_closing.consistent_keyframes = r.integer({"LoopClosing.ConsistentKeyframes"});
  s.loop_closing.max_drift_percent = r.number({"LoopClosing.MaxDriftPercent"});
  s.loop_closing.max_drift_deg_per_100m = r.number({"LoopClosing.MaxDriftDegPer100m"});
  s.loop_closing.fuse = flag("LoopClosing.Fuse");
  s.loop_closing.global_ba = flag("LoopClosing.GlobalBA");
  s.loop_closing.merge_maps = flag("LoopClosing.MergeMaps");
  s.loop_closing.scans = flag("LoopClosing.Scans");
  s.loop_closing.bridge = flag("LoopClosing.BridgeGaps");
  s.loop_closing.bridge_max_gap_s = r.number({"LoopClosing.BridgeMaxGap"});
  s.place_culling = flag("LocalMapping.PlaceCulling");
  s.lidar_pair_sigma = r.number({"LocalMapping.LidarPairSigma"});
  if (s.lidar_pair_sigma && !(*s.lidar_pair_sigma >= 0.0 && *s.lidar_pair_sigma <= 1.0))
    r.fail("LocalMapping.LidarPairSigma", "a sigma from 0 (off) to 1 m");
  s.lidar_pair_agreeing_sigma = r.number({"LocalMapping.LidarPairAgreeingSigma"});
  if (s.lidar_pair_agreeing_sigma && !(*s.lidar_pair_agreeing_sigma >= 0.0 && *s.lidar_pair_agreeing_sigma <= 1.0))
    r.fail("LocalMapping.LidarPairAgreeingSigma", "a sigma from 0 (as LidarPairSigma) to 1 m");
  s.lidar_pair_sigma_rotation = r.number({"LocalMapping.LidarPairSigmaRotation"});
  if (s.lidar_pair_sigma_rotation && !(*s.lidar_pair_sigma_rotation > 0.0 && *s.lidar_pair_sigma_rotation <= 0.1))
    r.fail("LocalMapping.LidarPairSigmaRotation", "a sigma above 0 and at most 0.1 rad");
  s.reference_landmark_ratio = r.number({"Tracking.ReferenceLandmarkRatio"});
  if (s.reference_landmark_ratio && !(*s.reference_landmark_ratio >= 0.0 && *s.reference_landmark_ratio <= 1.0))
    r.fail("Tracking.ReferenceLandmarkRatio", "a share from 0 (off) to 1");
  s.bounded_depth_error = flag("Tracking.BoundedDepthError");
  s.cauchy_weights = flag("Tracking.CauchyWeights");
  s.object_test = flag("Tracking.ObjectTest");
  s.direction_prior = flag("Tracking.DirectionPrior");
  s.register_gaps = flag("Tracking.RegisterGaps");
  s.register_lost = flag("Tracking.RegisterLost");
  s.register_refused_steps = flag("Tracking.RegisterRefusedSteps");
  s.road_start = flag("Tracking.RoadStart");
  s.start_by_rays = flag("Tracking.StartByRays");
  s.confirm_suspect_by_scan = flag("Tracking.ConfirmSuspectByScan");
  s.start_doubt_s = r.number({"Tracking.StartDoubt"});
  if (s.start_doubt_s && !(*s.start_doubt_s >= 0.0 && *s.start_doubt_s <= 60.0))
    r.fail("Tracking.StartDoubt", "seconds from 0 (off) to 60");
  s.speed_window_s = r.number({"Tracking.SpeedWindow"});
  if (s.speed_window_s && !(*s.speed_window_s >= 0.0 && *s.speed_window_s <= 5.0))
    r.fail("Tracking.SpeedWindow", "seconds from 0 (off) to 5");
  s.ransac_points_near_prior = r.integer({"Tracking.RansacPointsNearPrior"});
  if (s.ransac_points_near_prior && *s.ransac_points_near_prior < 3)
    r.fail("Tracking.RansacPointsNearPrior", "at least 3 keypoints (a rigid motion needs 3 points)");
  s.ransac_points_near_prior_retry = r.integer({"Tracking.RansacPointsNearPriorRetry"});
  if (s.ransac_points_near_prior_retry && *s.ransac_points_near_prior_retry < 0)
    r.fail("Tracking.RansacPointsNearPriorRetry", "a number of keypoints >= 0 (0 = no second RANSAC)");
  s.depth_consistency = flag("LocalMapping.DepthConsistency");
  s.triangulation = flag("LocalMapping.Triangulation");

  if (!(s.projection.min_depth >= 0.0F)) r.fail("LiDAR.min_dist", "a distance >= 0 m");
  if (!(s.projection.max_depth > s.projection.min_depth))
    r.fail("LiDAR.max_dist", "a distance greater than LiDAR.min_dist");
  try {
    s.orb.validate();
    s.loop_closing.validate();
  } catch (const ConfigError& e) {
    throw ParseError(yaml, 0, fmt::format("key '{}': {}", e.key(), e.what()));
  }
  for (const auto& key : r.unused())
    s.warnings.push_back(fmt::format("{}: unknown key '{}' ignored", yaml.string(), key));
  return s;
}

}  // namespace rgbl
