// rgbl vocab train <image folders...> --out <file>
// A bag-of-words vocabulary for loop closing from the images of one or more folders (every .png,
// .jpg and .jpeg, in name order, as grayscale), with the extractor rgbl tracks with. Deterministic:
// the same images and options give the same bytes. The shipped vocabulary is made this way
// (docs/loop-closing.md).
#include "command.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/features/orb.hpp"
#include "rgbl/place/vocabulary.hpp"

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace rgbl::cli {
namespace {

namespace fs = std::filesystem;

struct VocabArgs {
  std::vector<std::string> folders;
  std::string out;
  VocabularyOptions vocabulary;
  int features = 2000;
  std::size_t every = 1;
};

bool is_image(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

int train(const VocabArgs& args) {
  args.vocabulary.validate();
  const Stopwatch watch;
  std::vector<fs::path> images;
  for (const std::string& folder : args.folders) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) throw ParseError(folder, 0, "not a folder (expected a folder of images)");
    std::vector<fs::path> here;
    for (const auto& entry : fs::directory_iterator(folder)) {
      if (entry.is_regular_file() && is_image(entry.path())) here.push_back(entry.path());
    }
    std::sort(here.begin(), here.end());
    if (here.empty()) throw ParseError(folder, 0, "holds no .png/.jpg image");
    for (std::size_t i = 0; i < here.size(); i += args.every) images.push_back(here[i]);
  }
  OrbOptions orb;
  orb.num_features = args.features;
  OrbExtractor extractor(orb);
  std::vector<std::vector<Descriptor>> descriptors;
  std::vector<Keypoint> keypoints;
  std::size_t total = 0;
  for (const fs::path& image : images) {
    const cv::Mat gray = cv::imread(image.string(), cv::IMREAD_GRAYSCALE);
    if (gray.empty()) throw ParseError(image, 0, "cannot be read as an image");
    descriptors.emplace_back();
    extractor.extract(gray, keypoints, descriptors.back());
    total += descriptors.back().size();
  }
  const double extract_s = watch.elapsed_ms() / 1000.0;
  const Vocabulary vocabulary = Vocabulary::train(descriptors, args.vocabulary);
  vocabulary.save(args.out);
  fmt::print("vocabulary: {} words ({} nodes, branching {}, {} levels) from {} descriptors of {} images in {} "
             "folder(s); extraction {:.1f} s, training {:.1f} s\nwritten: {} ({} bytes)\n",
             vocabulary.words(), vocabulary.nodes(), vocabulary.branching(), vocabulary.levels(), total,
             images.size(), args.folders.size(), extract_s, watch.elapsed_ms() / 1000.0 - extract_s, args.out,
             fs::file_size(args.out));
  return 0;
}

}  // namespace

Command add_vocab_command(CLI::App& parent) {
  auto* app = parent.add_subcommand("vocab", "Bag-of-words vocabularies for loop closing");
  app->require_subcommand(1, 1);
  auto args = std::make_shared<VocabArgs>();
  auto* train_app = app->add_subcommand(
      "train", "Train a vocabulary on the images of one or more folders (deterministic: same images, same bytes)");
  train_app->add_option("folders", args->folders, "Folders of images (.png, .jpg), each read in name order")
      ->required();
  train_app->add_option("--out", args->out, "Vocabulary file to write")->required();
  train_app->add_option("--branching", args->vocabulary.branching, "Children per node")
      ->capture_default_str()
      ->check(CLI::Range(2, 64));
  train_app->add_option("--levels", args->vocabulary.levels, "Depth of the tree (words: up to branching^levels)")
      ->capture_default_str()
      ->check(CLI::Range(1, 8));
  train_app->add_option("--iterations", args->vocabulary.iterations, "k-medians rounds per node")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  train_app->add_option("--seed", args->vocabulary.seed, "Seed of the k-means++ initialisation")->capture_default_str();
  train_app->add_option("--features", args->features, "ORB features per image")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  train_app->add_option("--every", args->every, "Use every N-th image of each folder")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  return {app, [args, train_app] { return train_app->parsed() ? train(*args) : 2; }};
}

}  // namespace rgbl::cli
