// A downstream program: projects one synthetic point and checks where it lands.
#include <rgbl/geometry/projection.hpp>
#include <rgbl/version.hpp>

#include <cstdio>
#include <vector>

int main() {
  rgbl::Matrix34d P;
  P << 100.0, 0.0, 32.0, 0.0, 0.0, 100.0, 24.0, 0.0, 0.0, 0.0, 1.0, 0.0;
  const std::vector<rgbl::LidarPoint> cloud = {{0.0F, 0.0F, 10.0F, 0.0F}};
  const cv::Mat_<float> depth = rgbl::project_to_depth(cloud, P, 64, 48);
  const bool ok = depth(24, 32) == 10.0F;
  std::printf("rgbl %s consumer: %s\n", RGBL_VERSION_STRING, ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}
