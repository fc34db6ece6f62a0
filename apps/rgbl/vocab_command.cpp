// rgbl vocab train <image folders...> --out <file>
// A bag-of-words vocabulary for loop closing from the images of one or more folders (every .png,
// .jpg and .jpeg, in name order, as grayscale), with the extractor rgbl tracks with. Deterministic:
// the same images and options give the same bytes. The shipped vocabulary is made this way
// (docs/loop-closing.md).
#include "command.hpp"

#include "rgbl/pipeline/vocabulary_training.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <vector>

namespace rgbl::cli {
namespace {

struct VocabArgs {
  std::vector<std::filesystem::path> folders;
  std::filesystem::path out;
  VocabularyTrainingOptions options;
};

int train(const VocabArgs& args) {
  const VocabularyTraining t = train_vocabulary(args.folders, args.options);
  t.vocabulary.save(args.out);
  fmt::print("vocabulary: {} words ({} nodes, branching {}, {} levels) from {} descriptors of {} images in {} "
             "folder(s); extraction {:.1f} s, training {:.1f} s\nwritten: {} ({} bytes)\n",
             t.vocabulary.words(), t.vocabulary.nodes(), t.vocabulary.branching(), t.vocabulary.levels(),
             t.descriptors, t.images, args.folders.size(), t.extraction_s, t.training_s, args.out.string(),
             std::filesystem::file_size(args.out));
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
  train_app->add_option("--branching", args->options.vocabulary.branching, "Children per node")
      ->capture_default_str()
      ->check(CLI::Range(2, 64));
  train_app->add_option("--levels", args->options.vocabulary.levels, "Depth of the tree (words: up to branching^levels)")
      ->capture_default_str()
      ->check(CLI::Range(1, 8));
  train_app->add_option("--iterations", args->options.vocabulary.iterations, "k-medians rounds per node")
      ->capture_default_str()
      ->check(whole_number(1));
  train_app->add_option("--seed", args->options.vocabulary.seed, "Seed of the k-means++ initialisation")->capture_default_str();
  train_app->add_option("--features", args->options.orb.num_features, "ORB features per image")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  train_app->add_option("--every", args->options.every, "Use every N-th image of each folder")
      ->capture_default_str()
      ->check(whole_number(1));
  return {app, [args, train_app] { return train_app->parsed() ? train(*args) : 2; }};
}

}  // namespace rgbl::cli
