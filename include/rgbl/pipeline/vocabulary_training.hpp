#pragma once
// What `rgbl vocab train` does: a bag-of-words vocabulary from the images of folders, with the ORB
// extractor rgbl tracks with. Deterministic: the same images and options give the same bytes.

#include "rgbl/features/orb.hpp"
#include "rgbl/place/vocabulary.hpp"

#include <cstddef>
#include <filesystem>
#include <vector>

namespace rgbl {

struct VocabularyTrainingOptions {
  VocabularyOptions vocabulary;
  OrbOptions orb;         // num_features per image (default 2000 here)
  std::size_t every = 1;  // every N-th image of each folder

  VocabularyTrainingOptions() { orb.num_features = 2000; }
  void validate() const;  // throws ConfigError naming the option
};

struct VocabularyTraining {
  Vocabulary vocabulary;
  std::size_t images = 0, descriptors = 0;
  double extraction_s = 0.0, training_s = 0.0;
};

// Every .png/.jpg/.jpeg of each folder, in name order, read as grey. Throws ParseError naming a
// folder that is none or holds no image, or an image that cannot be read.
VocabularyTraining train_vocabulary(const std::vector<std::filesystem::path>& folders,
                                    const VocabularyTrainingOptions& options = {});

}  // namespace rgbl
