#include "rgbl/core/error.hpp"
#include "rgbl/features/orb.hpp"
#include "rgbl/io/settings.hpp"
#include "support/parse_error.hpp"
#include "support/temp_dir.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>

using Catch::Matchers::Contains;

namespace {

// Shaped like the RGB-L reference's KITTI04-12.yaml (values of sequence 04).
const char* kRgblYaml = R"(%YAML:1.0
File.version: "1.0"
Camera.type: "PinHole"
Camera.fx: 707.0912
Camera.fy: 707.0912
Camera.cx: 601.8873
Camera.cy: 183.1104
Camera.k1: 0.0
Camera.k2: 0.0
Camera.p1: 0.0
Camera.p2: 0.0
Camera.width: 1226
Camera.height: 370
Camera.fps: 10.0
Camera.bf: 379.8145
Camera.RGB: 1
ThDepth: 40.0
DepthMapFactor: 1.0
ORBextractor.nFeatures: 2000
ORBextractor.scaleFactor: 1.2
ORBextractor.nLevels: 8
ORBextractor.iniThFAST: 20
ORBextractor.minThFAST: 7
LiDAR.Method: "InverseDilation"
LiDAR.min_dist: 5.0
LiDAR.max_dist: 200.0
LiDAR.Tr11: -1.857739385241e-03
LiDAR.Tr12: -9.999659513510e-01
LiDAR.Tr13: -8.039975204516e-03
LiDAR.Tr14: -4.784029760483e-03
LiDAR.Tr21: -6.481465826011e-03
LiDAR.Tr22: 8.051860151134e-03
LiDAR.Tr23: -9.999466081774e-01
LiDAR.Tr24: -7.337429464231e-02
LiDAR.Tr31: 9.999773098287e-01
LiDAR.Tr32: -1.805528627661e-03
LiDAR.Tr33: -6.496203536139e-03
LiDAR.Tr34: -3.339968064433e-01
LiDAR.MethodInverseDilation.KernelType: "Diamond"
LiDAR.MethodInverseDilation.KernelSize_u: 5
Viewer.KeyFrameSize: 0.6
MySetting.Unknown: 3
)";

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  REQUIRE(pos != std::string::npos);
  return text.replace(pos, from.size(), to);
}

std::string error_of(const std::filesystem::path& file) {
  return rgbl::test::parse_error_message([&] { rgbl::read_settings(file); }, file);
}

// The reference file with one more ORBextractor line.
std::string with_orb_line(const std::string& line) {
  return replace(kRgblYaml, "ORBextractor.minThFAST: 7", "ORBextractor.minThFAST: 7\n" + line);
}

}  // namespace

TEST_CASE("settings: ORB-SLAM and RGB-L keys map onto rgbl values", "[io][settings]") {
  rgbl::test::TempDir tmp;
  const auto s = rgbl::read_settings(tmp.write("kitti04.yaml", kRgblYaml));
  REQUIRE(s.camera);
  CHECK(s.camera->fx == 707.0912);
  CHECK(s.camera->cy == 183.1104);
  CHECK(s.camera->width == 1226);
  CHECK(s.camera->height == 370);
  CHECK(s.camera->distortion.is_zero());
  CHECK(s.fps == 10.0);
  CHECK(s.bf == 379.8145);
  CHECK(s.rgb_order == true);
  CHECK(s.th_depth == 40.0);
  CHECK(s.depth_map_factor == 1.0);
  CHECK(s.orb.n_features == 2000);
  CHECK(s.orb.scale_factor == 1.2);
  CHECK(s.orb.n_levels == 8);
  CHECK(s.orb.ini_th_fast == 20);
  CHECK(s.orb.min_th_fast == 7);
  CHECK_FALSE(s.orb.features_per_node);
  CHECK(s.lidar_method == "InverseDilation");
  CHECK(s.projection.min_depth == 5.0F);
  CHECK(s.projection.max_depth == 200.0F);
  REQUIRE(s.T_cam_lidar);
  CHECK(s.T_cam_lidar->matrix()(0, 1) == -9.999659513510e-01);
  CHECK(s.T_cam_lidar->matrix()(2, 3) == -3.339968064433e-01);
  CHECK(s.T_cam_lidar->matrix().row(3) == Eigen::RowVector4d(0, 0, 0, 1));
  CHECK(s.kernel_type == "Diamond");
  CHECK(s.kernel_size == 5);
  REQUIRE(s.warnings.size() == 1);  // Viewer.* and File.version are known ORB-SLAM keys
  CHECK_THAT(s.warnings[0], Contains("unknown key 'MySetting.Unknown'"));
}

TEST_CASE("settings: ORB-SLAM3's Camera1 prefix and files without the %YAML line", "[io][settings]") {
  rgbl::test::TempDir tmp;
  const auto s = rgbl::read_settings(tmp.write(
      "v1.yaml", "Camera1.fx: 500.0\nCamera1.fy: 501\nCamera1.cx: 300\nCamera1.cy: 200\nCamera1.k1: -0.25\n"));
  REQUIRE(s.camera);
  CHECK(s.camera->fy == 501.0);
  CHECK(s.camera->distortion.k1 == -0.25);
  CHECK(s.camera->width == 0);
}

TEST_CASE("settings: a minimal file gives the defaults", "[io][settings]") {
  rgbl::test::TempDir tmp;
  const auto s = rgbl::read_settings(tmp.write("min.yaml", "%YAML:1.0\nORBextractor.nFeatures: 1500\n"));
  CHECK_FALSE(s.camera);
  CHECK_FALSE(s.orb.features_per_node);
  CHECK_FALSE(s.T_cam_lidar);
  CHECK(s.orb.n_features == 1500);
  CHECK(s.orb.n_levels == 8);
  // Keys the file leaves out are the extractor's own defaults: a settings file changes only what it names.
  const rgbl::OrbOptions orb;
  CHECK(s.orb.ini_th_fast == orb.fast_threshold);
  CHECK(s.orb.min_th_fast == orb.fast_min_threshold);
  CHECK(s.orb.scale_factor == Approx(orb.scale_factor));
  CHECK(s.orb.n_levels == orb.num_levels);
  CHECK(s.projection.min_depth == 5.0F);
  CHECK(s.kernel_size == 0);
  CHECK_FALSE(s.loop_closing.enabled);
  CHECK_FALSE(s.loop_closing.max_drift_percent);
  CHECK(s.warnings.empty());
}

TEST_CASE("settings: rgbl's LoopClosing keys", "[io][settings]") {
  rgbl::test::TempDir tmp;
  const auto s = rgbl::read_settings(
      tmp.write("loop.yaml", "%YAML:1.0\nLoopClosing.Enabled: 0\nLoopClosing.MaxPlaceDistance: 0.3\n"
                             "LoopClosing.ConsistentKeyframes: 4\nLoopClosing.MaxDriftPercent: 5\n"
                             "LoopClosing.MaxDriftDegPer100m: 4.5\nLoopClosing.Fuse: 1\nLoopClosing.GlobalBA: 1\n"
                             "LoopClosing.MergeMaps: 0\nLoopClosing.BridgeGaps: 0\nLoopClosing.BridgeMaxGap: 2.5\n"
                             "LoopClosing.Scans: 0\n"
                             "LoopClosing.Places: \"scan_context, bow\"\n"
                             "LoopClosing.Vocabulary: \"voc/mine.rgblvoc\"\n"));
  CHECK(s.loop_closing.enabled == false);
  CHECK(s.loop_closing.places == std::vector<std::string>{"scan_context", "bow"});
  CHECK(s.loop_closing.vocabulary == tmp.path() / "voc/mine.rgblvoc");  // relative to the settings file
  CHECK(s.loop_closing.max_place_distance == 0.3);
  CHECK(s.loop_closing.consistent_keyframes == 4);
  CHECK(s.loop_closing.max_drift_percent == 5.0);
  CHECK(s.loop_closing.max_drift_deg_per_100m == 4.5);
  CHECK(s.loop_closing.fuse == true);
  CHECK(s.loop_closing.global_ba == true);  // off by default
  CHECK(s.loop_closing.merge_maps == false);
  CHECK(s.loop_closing.bridge == false);
  CHECK(s.loop_closing.bridge_max_gap_s == 2.5);
  CHECK(s.loop_closing.scans == false);
  CHECK(s.warnings.empty());
  CHECK_THAT(error_of(tmp.write("l1.yaml", "%YAML:1.0\nLoopClosing.Enabled: 2\n")),
             Contains("'LoopClosing.Enabled': expected 0 (off) or 1 (on)"));
  CHECK_THAT(error_of(tmp.write("l2.yaml", "%YAML:1.0\nLoopClosing.MaxPlaceDistance: 1.5\n")),
             Contains("'LoopClosing.MaxPlaceDistance': expected a Scan Context distance in (0, 1]"));
  CHECK_THAT(error_of(tmp.write("l4.yaml", "%YAML:1.0\nLoopClosing.Places: \"bow,\"\n")),
             Contains("'LoopClosing.Places': expected place recogniser names separated by commas"));
  CHECK_THAT(error_of(tmp.write("l5.yaml", "%YAML:1.0\nLoopClosing.Vocabulary: \"\"\n")),
             Contains("'LoopClosing.Vocabulary': expected a vocabulary file"));
  CHECK_THAT(error_of(tmp.write("l3.yaml", "%YAML:1.0\nLoopClosing.ConsistentKeyframes: 0\n")),
             Contains("'LoopClosing.ConsistentKeyframes': expected a count >= 1"));
  CHECK_THAT(error_of(tmp.write("l4.yaml", "%YAML:1.0\nLoopClosing.MaxDriftPercent: -1\n")),
             Contains("'LoopClosing.MaxDriftPercent': expected a percentage > 0"));
  CHECK_THAT(error_of(tmp.write("l5.yaml", "%YAML:1.0\nLoopClosing.GlobalBA: yes\n")),
             Contains("LoopClosing.GlobalBA"));
  CHECK_THAT(error_of(tmp.write("l6.yaml", "%YAML:1.0\nLoopClosing.BridgeMaxGap: 0\n")),
             Contains("'LoopClosing.BridgeMaxGap': expected seconds > 0"));
}

TEST_CASE("settings: rgbl's LiDAR occlusion keys", "[io][settings]") {
  rgbl::test::TempDir tmp;
  const auto s = rgbl::read_settings(
      tmp.write("occ.yaml", "%YAML:1.0\nLiDAR.OcclusionWindowDeg: 0\nLiDAR.OcclusionRatio: 1.5\n"));
  CHECK(s.occlusion_window_deg == 0.0);
  CHECK(s.occlusion_ratio == 1.5);
  CHECK(s.warnings.empty());
  const auto unset = rgbl::read_settings(tmp.write("unset.yaml", "%YAML:1.0\nCamera.fps: 10\n"));
  CHECK_FALSE(unset.occlusion_window_deg);
  CHECK_FALSE(unset.occlusion_ratio);
  CHECK_THAT(error_of(tmp.write("w.yaml", "%YAML:1.0\nLiDAR.OcclusionWindowDeg: -0.1\n")),
             Contains("'LiDAR.OcclusionWindowDeg': expected 0 (off) .. 5 deg"));
  CHECK_THAT(error_of(tmp.write("r.yaml", "%YAML:1.0\nLiDAR.OcclusionRatio: 1\n")),
             Contains("'LiDAR.OcclusionRatio': expected a depth ratio > 1"));
  const auto fit = rgbl::read_settings(tmp.write("fit.yaml", "%YAML:1.0\nLiDAR.SurfaceFitWindowDeg: 0.5\n"));
  CHECK(fit.surface_fit_window_deg == 0.5);
  CHECK_FALSE(unset.surface_fit_window_deg);
  CHECK_THAT(error_of(tmp.write("f.yaml", "%YAML:1.0\nLiDAR.SurfaceFitWindowDeg: 5\n")),
             Contains("'LiDAR.SurfaceFitWindowDeg': expected 0 (off) .. 5 deg"));
  CHECK(rgbl::read_settings(tmp.write("st.yaml", "%YAML:1.0\nLiDAR.SurfaceStepPx: 4\n")).surface_step_px == 4);
  CHECK_FALSE(unset.surface_step_px);
  CHECK_THAT(error_of(tmp.write("st0.yaml", "%YAML:1.0\nLiDAR.SurfaceStepPx: 0\n")),
             Contains("'LiDAR.SurfaceStepPx': expected 1 .. 15 px"));
  CHECK(rgbl::read_settings(tmp.write("k.yaml", "%YAML:1.0\nLiDAR.KernelFromRingSpacing: 0\n")).kernel_from_ring_spacing ==
        false);
  CHECK_FALSE(unset.kernel_from_ring_spacing);
  CHECK_THAT(error_of(tmp.write("k2.yaml", "%YAML:1.0\nLiDAR.KernelFromRingSpacing: 2\n")),
             Contains("'LiDAR.KernelFromRingSpacing'"));
  const auto registration = rgbl::read_settings(tmp.write("g.yaml", "%YAML:1.0\nLiDAR.RegistrationSigmaDeg: 0.2\n"));
  CHECK(registration.registration_sigma_deg == 0.2);
  CHECK_FALSE(unset.registration_sigma_deg);
  CHECK_THAT(error_of(tmp.write("g2.yaml", "%YAML:1.0\nLiDAR.RegistrationSigmaDeg: -1\n")),
             Contains("'LiDAR.RegistrationSigmaDeg': expected 0 (off) .. 5 deg"));
}

TEST_CASE("settings: LiDAR.TimeOffset, the image's time minus the scan's", "[io][settings]") {
  rgbl::test::TempDir tmp;
  CHECK(rgbl::read_settings(tmp.write("t.yaml", "%YAML:1.0\nLiDAR.TimeOffset: 0.0169\n")).scan_time_offset == 0.0169);
  CHECK(rgbl::read_settings(tmp.write("z.yaml", "%YAML:1.0\nLiDAR.TimeOffset: 0\n")).scan_time_offset == 0.0);
  CHECK_FALSE(rgbl::read_settings(tmp.write("unset.yaml", "%YAML:1.0\nCamera.fps: 10\n")).scan_time_offset);
  CHECK_THAT(error_of(tmp.write("far.yaml", "%YAML:1.0\nLiDAR.TimeOffset: 1.5\n")),
             Contains("'LiDAR.TimeOffset': expected seconds from the scan to the image, -1 .. 1"));
}

TEST_CASE("settings: LocalMapping.PlaceCulling switches keyframe culling by revisits", "[io][settings]") {
  rgbl::test::TempDir tmp;
  const auto off = rgbl::read_settings(tmp.write("off.yaml", "%YAML:1.0\nLocalMapping.PlaceCulling: 0\n"));
  CHECK(off.place_culling == false);
  CHECK(off.warnings.empty());
  CHECK_FALSE(rgbl::read_settings(tmp.write("unset.yaml", "%YAML:1.0\nCamera.fps: 10\n")).place_culling);
  CHECK_THAT(error_of(tmp.write("bad.yaml", "%YAML:1.0\nLocalMapping.PlaceCulling: 3\n")),
             Contains("'LocalMapping.PlaceCulling': expected 0 (off) or 1 (on)"));
}

TEST_CASE("settings: the LiDAR pair's sigmas and the scan samples' elevation correction, read and validated",
          "[io][settings]") {
  // key, a value it takes, where it lands, a value it refuses and what the error says is expected
  struct Key {
    const char* name;
    double value;
    std::optional<double> rgbl::Settings::*field;
    const char* refused;
    const char* expected;
  };
  const Key keys[] = {
      {"LocalMapping.LidarPairSigma", 0.01, &rgbl::Settings::lidar_pair_sigma, "2", "a sigma from 0 (off) to 1 m"},
      // 0 would divide the pair's residual by zero: the pair is switched off by LidarPairSigma alone
      {"LocalMapping.LidarPairSigmaRotation", 0.0007, &rgbl::Settings::lidar_pair_sigma_rotation, "0",
       "a sigma above 0 and at most 0.1 rad"},
      {"LocalMapping.LidarPairAgreeingSigma", 0.01, &rgbl::Settings::lidar_pair_agreeing_sigma, "1.5",
       "a sigma from 0 (as LidarPairSigma) to 1 m"},
      {"LiDAR.ElevationCorrection", 0.205, &rgbl::Settings::elevation_correction_deg, "5",
       "an angle in deg, -2 .. 2"},
  };
  rgbl::test::TempDir tmp;
  const auto unset = rgbl::read_settings(tmp.write("unset.yaml", "%YAML:1.0\nCamera.fps: 10\n"));
  for (const Key& key : keys) {
    INFO(key.name);
    const auto s = rgbl::read_settings(tmp.write("t.yaml", fmt::format("%YAML:1.0\n{}: {}\n", key.name, key.value)));
    CHECK(s.*key.field == key.value);
    CHECK(s.warnings.empty());
    CHECK_FALSE(unset.*key.field);
    CHECK_THAT(error_of(tmp.write("bad.yaml", fmt::format("%YAML:1.0\n{}: {}\n", key.name, key.refused))),
               Contains(fmt::format("'{}': expected {}", key.name, key.expected)));
  }
}

TEST_CASE("settings: Tracking.ReferenceLandmarkRatio, BoundedDepthError, RegisterGaps, CauchyWeights, ObjectTest, DirectionPrior, RegisterRefusedSteps, StartDoubt, SpeedWindow, RansacPointsNearPrior(Retry), LocalMapping.DepthConsistency and Triangulation, read and validated", "[io][settings]") {
  rgbl::test::TempDir tmp;
  const auto s = rgbl::read_settings(tmp.write(
      "t.yaml", "%YAML:1.0\nTracking.ReferenceLandmarkRatio: 0.25\nTracking.BoundedDepthError: 1\nTracking.RegisterGaps: 0\n"
                "Tracking.CauchyWeights: 0\nTracking.ObjectTest: 1\nTracking.DirectionPrior: 0\n"
                "Tracking.RegisterRefusedSteps: 0\nTracking.RansacPointsNearPrior: 500\n"
                "Tracking.RansacPointsNearPriorRetry: 0\nTracking.StartDoubt: 0.5\nTracking.SpeedWindow: 0.4\n"
                "Tracking.RoadStart: 0\nTracking.StartByRays: 0\nTracking.ConfirmSuspectByScan: 0\n"
                "LocalMapping.DepthConsistency: 1\nLocalMapping.Triangulation: 1\n"));
  REQUIRE(s.reference_landmark_ratio);
  CHECK(*s.reference_landmark_ratio == 0.25);
  CHECK(s.bounded_depth_error == true);
  CHECK(s.register_gaps == false);
  CHECK(s.cauchy_weights == false);
  CHECK(s.object_test == true);
  CHECK(s.direction_prior == false);
  CHECK(s.depth_consistency == true);
  CHECK(s.triangulation == true);
  CHECK(s.register_refused_steps == false);
  CHECK(s.ransac_points_near_prior == 500);
  CHECK(s.ransac_points_near_prior_retry == 0);
  CHECK(s.start_doubt_s == 0.5);
  CHECK(s.speed_window_s == 0.4);
  CHECK(s.road_start == false);
  CHECK(s.start_by_rays == false);
  CHECK(s.confirm_suspect_by_scan == false);
  CHECK(s.warnings.empty());
  const auto unset = rgbl::read_settings(tmp.write("unset.yaml", "%YAML:1.0\nCamera.fps: 10\n"));
  CHECK_FALSE(unset.reference_landmark_ratio);
  CHECK_FALSE(unset.bounded_depth_error);
  CHECK_FALSE(unset.register_gaps);
  CHECK_FALSE(unset.cauchy_weights);
  CHECK_FALSE(unset.object_test);
  CHECK_FALSE(unset.direction_prior);
  CHECK_FALSE(unset.depth_consistency);
  CHECK_FALSE(unset.triangulation);
  CHECK_FALSE(unset.register_refused_steps);
  CHECK_FALSE(unset.ransac_points_near_prior);
  CHECK_FALSE(unset.ransac_points_near_prior_retry);
  CHECK_FALSE(unset.start_doubt_s);
  CHECK_FALSE(unset.speed_window_s);
  CHECK_FALSE(unset.road_start);
  CHECK_FALSE(unset.start_by_rays);
  CHECK_FALSE(unset.confirm_suspect_by_scan);
  CHECK_THAT(error_of(tmp.write("window.yaml", "%YAML:1.0\nTracking.SpeedWindow: 6\n")),
             Contains("'Tracking.SpeedWindow': expected seconds from 0 (off) to 5"));
  CHECK_THAT(error_of(tmp.write("doubt.yaml", "%YAML:1.0\nTracking.StartDoubt: -1\n")),
             Contains("'Tracking.StartDoubt': expected seconds from 0 (off) to 60"));
  CHECK_THAT(error_of(tmp.write("refused.yaml", "%YAML:1.0\nTracking.RegisterRefusedSteps: 2\n")),
             Contains("'Tracking.RegisterRefusedSteps': expected 0 (off) or 1 (on)"));
  CHECK_THAT(error_of(tmp.write("points.yaml", "%YAML:1.0\nTracking.RansacPointsNearPrior: 2\n")),
             Contains("'Tracking.RansacPointsNearPrior': expected at least 3 keypoints"));
  CHECK_THAT(error_of(tmp.write("retry.yaml", "%YAML:1.0\nTracking.RansacPointsNearPriorRetry: -1\n")),
             Contains("'Tracking.RansacPointsNearPriorRetry': expected a number of keypoints >= 0"));
  CHECK_THAT(error_of(tmp.write("tri.yaml", "%YAML:1.0\nLocalMapping.Triangulation: 2\n")),
             Contains("'LocalMapping.Triangulation'"));
  CHECK_THAT(error_of(tmp.write("gaps.yaml", "%YAML:1.0\nTracking.RegisterGaps: yes\n")),
             Contains("'Tracking.RegisterGaps'"));
  CHECK_THAT(error_of(tmp.write("ratio.yaml", "%YAML:1.0\nTracking.ReferenceLandmarkRatio: 1.5\n")),
             Contains("'Tracking.ReferenceLandmarkRatio': expected a share from 0 (off) to 1"));
  CHECK_THAT(error_of(tmp.write("flag.yaml", "%YAML:1.0\nTracking.BoundedDepthError: 2\n")),
             Contains("'Tracking.BoundedDepthError': expected 0 (off) or 1 (on)"));
  CHECK_THAT(error_of(tmp.write("objects.yaml", "%YAML:1.0\nTracking.ObjectTest: 3\n")),
             Contains("'Tracking.ObjectTest': expected 0 (off) or 1 (on)"));
  CHECK_THAT(error_of(tmp.write("cauchy.yaml", "%YAML:1.0\nTracking.CauchyWeights: -1\n")),
             Contains("'Tracking.CauchyWeights': expected 0 (off) or 1 (on)"));
  CHECK_THAT(error_of(tmp.write("direction.yaml", "%YAML:1.0\nTracking.DirectionPrior: 2\n")),
             Contains("'Tracking.DirectionPrior': expected 0 (off) or 1 (on)"));
  CHECK_THAT(error_of(tmp.write("consistency.yaml", "%YAML:1.0\nLocalMapping.DepthConsistency: 2\n")),
             Contains("'LocalMapping.DepthConsistency': expected 0 (off) or 1 (on)"));
}

TEST_CASE("settings: wrong types, incomplete groups and bad values name file and key", "[io][settings][bad-input]") {
  rgbl::test::TempDir tmp;
  CHECK_THAT(error_of(tmp.write("a.yaml", replace(kRgblYaml, "LiDAR.min_dist: 5.0", "LiDAR.min_dist: \"five\""))),
             Contains("key 'LiDAR.min_dist': expected a number, found the string 'five'"));
  CHECK_THAT(error_of(tmp.write("b.yaml", replace(kRgblYaml, "ORBextractor.nLevels: 8", "ORBextractor.nLevels: 8.5"))),
             Contains("key 'ORBextractor.nLevels': expected an integer"));
  CHECK_THAT(error_of(tmp.write("c.yaml", replace(kRgblYaml, "Camera.cy: 183.1104\n", ""))),
             Contains("key 'Camera.cy'"));
  CHECK_THAT(error_of(tmp.write("d.yaml", replace(kRgblYaml, "LiDAR.Tr23: -9.999466081774e-01\n", ""))),
             Contains("key 'LiDAR.Tr23'"));
  CHECK_THAT(error_of(tmp.write("e.yaml", replace(kRgblYaml, "LiDAR.Method: \"InverseDilation\"", "LiDAR.Method: 3"))),
             Contains("key 'LiDAR.Method': expected a string"));
  CHECK_THAT(error_of(tmp.write("f.yaml", replace(kRgblYaml, "LiDAR.max_dist: 200.0", "LiDAR.max_dist: 2.0"))),
             Contains("key 'LiDAR.max_dist'"));
  CHECK_THAT(error_of(tmp.write("g.yaml", replace(kRgblYaml, "KernelSize_u: 5", "KernelSize_u: 4"))),
             Contains("KernelSize_u': expected an odd kernel size"));
  CHECK_THAT(
      error_of(tmp.write("h.yaml", replace(kRgblYaml, "ORBextractor.minThFAST: 7", "ORBextractor.minThFAST: 30"))),
      Contains("ORBextractor.minThFAST"));
  CHECK_THAT(error_of(tmp.write("h2.yaml", with_orb_line("ORBextractor.featuresPerNode: 0"))),
             Contains("'ORBextractor.featuresPerNode': expected a count >= 1"));
  CHECK_THAT(error_of(tmp.write("h3.yaml", with_orb_line("ORBextractor.spreadFraction: 1.5"))),
             Contains("'ORBextractor.spreadFraction': expected a fraction in (0, 1]"));
  CHECK_THAT(error_of(tmp.write("i.yaml", replace(kRgblYaml, "LiDAR.Tr11: -1.857739385241e-03", "LiDAR.Tr11: 2.0"))),
             Contains("rotation matrix"));
  CHECK_THAT(error_of(tmp.write("j.yaml", "%YAML:1.0\nCamera.fx: [1, 2\n")), Contains("j.yaml"));
  CHECK_THAT(error_of(tmp.write("k.yaml", "just some text\n")), Contains("not a readable YAML settings file"));
  CHECK_THAT(error_of(tmp.write("l.yaml", "\n")), Contains("is empty"));
  CHECK_THAT(error_of(tmp.path() / "missing.yaml"), Contains("missing"));
  CHECK_THAT(error_of(tmp.path()), Contains("is a directory"));
}

TEST_CASE("settings: input on which OpenCV's parser throws standard exceptions is a ParseError", "[io][settings][bad-input]") {
  // Found by fuzz/fuzz_settings: OpenCV 4.6 let std::length_error escape FileStorage::open here.
  rgbl::test::TempDir tmp;
  const auto file = tmp.write("empty_key.yaml", "FrameSize: 0.05\nUnknown.key: [1, 2, 3]\nNested: { : { a: 1 \"x\" }\n");
  CHECK_THAT(error_of(file), Contains("empty_key.yaml") && Contains("not a readable YAML settings file"));
  CHECK_THAT(error_of(tmp.write("nested.yaml", "a: { : { b: 1 \"x\" }\n")), Contains("nested.yaml"));
  // Found by fuzz/fuzz_settings: OpenCV 4.6's parser never returned on this (document markers).
  CHECK_THAT(error_of(tmp.write("markers.yaml", "----s\n----\nL")), Contains("markers.yaml:1: expected 'Key: value'"));
  CHECK_THAT(error_of(tmp.write("two.yaml", "---\na: 1\n---\nb: 2\n")), Contains("two.yaml:3:"));
  // Found by fuzz/fuzz_settings: OpenCV 4.6's parser never returned on a key indented less than the first.
  CHECK_THAT(error_of(tmp.write("dedent.yaml", " t:0\nL::-\na")), Contains("dedent.yaml:2: expected 'Key: value' indented"));
  CHECK_THAT(error_of(tmp.write("dedent2.yaml", "  t: 0\n  # note\n L: -\na")),
             Contains("dedent2.yaml:3:") && Contains("line 1, 2 spaces"));
  // An indented top-level map is fine as long as every key keeps that indentation.
  CHECK(rgbl::read_settings(tmp.write("indented.yaml", "# c\n  Camera.fps: 10.0\n\n  Camera.RGB: 1\n")).fps == 10.0);
  // One plain document start is fine.
  CHECK(rgbl::read_settings(tmp.write("one.yaml", "%YAML:1.0\n---\nCamera.fps: 10.0\n")).fps == 10.0);
}

TEST_CASE("settings: deep nesting, duplicate keys and byte order marks", "[io][settings][bad-input]") {
  rgbl::test::TempDir tmp;
  // 50 000 nested brackets overflowed the stack inside OpenCV's YAML parser (SIGSEGV)
  const std::string deep = "a: " + std::string(50000, '[') + std::string(50000, ']') + "\n";
  CHECK_THAT(error_of(tmp.write("deep.yaml", deep)), Contains("deep.yaml:1: nested deeper than 64 levels"));
  CHECK_THAT(error_of(tmp.write("maps.yaml", "%YAML:1.0\nb: 1\na: " + std::string(70, '{') + "\n")),
             Contains("maps.yaml:3: nested deeper than 64 levels"));
  std::string block = "a:\n";
  for (int depth = 1; depth < 80; ++depth) block += std::string(static_cast<std::size_t>(depth), ' ') + "- \n";
  CHECK_THAT(error_of(tmp.write("block.yaml", block)), Contains("block.yaml:64: nested deeper than 64 levels"));
  // brackets in strings and comments do not count; a few levels are fine
  const auto quoted = tmp.write("quoted.yaml", "%YAML:1.0\nLiDAR.Method: \"" + std::string(100, '[') +
                                                   "\"  # " + std::string(100, '{') + "\nViewer.x: [[1, 2], [3]]\n");
  CHECK(rgbl::read_settings(quoted).lidar_method == std::string(100, '['));
  // the second of two equal keys used to win silently
  CHECK_THAT(error_of(tmp.write("dup.yaml", "%YAML:1.0\nORBextractor.nFeatures: 100\n# again\n"
                                            "ORBextractor.nFeatures: 200\n")),
             Contains("dup.yaml:4: key 'ORBextractor.nFeatures' given twice (lines 2 and 4)"));
  // ... and so did equal keys in a nested map (a matrix's); the same key in two maps is fine
  const std::string matrix = "%YAML:1.0\nORBextractor.nFeatures: 100\nTr: !!opencv-matrix\n  rows: 3\n  cols: 4\n"
                             "  rows: 4\n  dt: d\n  data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]\n";
  CHECK_THAT(error_of(tmp.write("nested.yaml", matrix)),
             Contains("nested.yaml:6: key 'rows' given twice (lines 4 and 6)"));
  const auto two_maps = tmp.write("two_maps.yaml", "%YAML:1.0\nA:\n  rows: 1\n  x:\n    rows: 2\nB:\n  rows: 3\n"
                                                   "list:\n  - rows: 1\n    cols: 2\n  - rows: 1\n    cols: 2\n"
                                                   "ORBextractor.nFeatures: 300\n");
  CHECK(rgbl::read_settings(two_maps).orb.n_features == 300);
  // a UTF-8 byte order mark (Windows editors) is skipped
  const auto bom = rgbl::read_settings(tmp.write("bom.yaml", "\xEF\xBB\xBFORBextractor.nFeatures: 1000\n"));
  CHECK(bom.orb.n_features == 1000);
  // intrinsics that cannot be a camera's
  CHECK_THAT(error_of(tmp.write("f.yaml", replace(kRgblYaml, "Camera.fx: 707.0912", "Camera.fx: 1e-300"))),
             Contains("key 'Camera.fx': expected plausible intrinsics"));
}
