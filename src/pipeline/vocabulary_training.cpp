#include "rgbl/pipeline/vocabulary_training.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/io/image.hpp"
#include "rgbl/core/timer.hpp"


#include <algorithm>
#include <cctype>
#include <string>
#include <system_error>

namespace rgbl {
namespace {

bool is_image(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

}  // namespace

void VocabularyTrainingOptions::validate() const {
  vocabulary.validate();
  orb.validate();
  require(every >= 1, "--every", "a stride of at least 1 image");
}

VocabularyTraining train_vocabulary(const std::vector<std::filesystem::path>& folders,
                                    const VocabularyTrainingOptions& options) {
  options.validate();
  const Stopwatch watch;
  std::vector<std::filesystem::path> images;
  for (const auto& folder : folders) {
    std::error_code ec;
    if (!std::filesystem::is_directory(folder, ec)) {
      throw ParseError(folder, 0, "not a folder (expected a folder of images)");
    }
    std::vector<std::filesystem::path> here;
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
      if (entry.is_regular_file() && is_image(entry.path())) here.push_back(entry.path());
    }
    std::sort(here.begin(), here.end());
    if (here.empty()) throw ParseError(folder, 0, "holds no .png/.jpg image");
    for (std::size_t i = 0; i < here.size(); i += options.every) images.push_back(here[i]);
  }
  OrbExtractor extractor(options.orb);
  std::vector<std::vector<Descriptor>> descriptors;
  std::vector<Keypoint> keypoints;
  VocabularyTraining out;
  for (const auto& image : images) {
    const cv::Mat gray = read_image_file(image, ImageMode::grey);
    descriptors.emplace_back();
    extractor.extract(gray, keypoints, descriptors.back());
    out.descriptors += descriptors.back().size();
  }
  out.images = images.size();
  out.extraction_s = watch.elapsed_ms() / 1000.0;
  out.vocabulary = Vocabulary::train(descriptors, options.vocabulary);
  out.training_s = watch.elapsed_ms() / 1000.0 - out.extraction_s;
  return out;
}

}  // namespace rgbl
