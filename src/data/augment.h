// Training-time augmentation of a tuple, deterministic from a seed: shared colour jitter, per-view zoom, mirror.
#pragma once
#include <cstdint>

namespace isplat {

class ConfigVisitor;
struct TupleSample;

struct AugmentOptions {
  double flip = 0;             // probability of mirroring the tuple left-right
  double zoom = 0;             // crop a window of 1/z of each side, z uniform in [1, 1 + zoom], resized back
  double brightness = 0;       // gain log-uniform in [1/(1+b), 1+b]
  double contrast = 0;         // contrast about mid-grey, factor log-uniform in [1/(1+c), 1+c]
  double saturation = 0;       // saturation factor log-uniform in [1/(1+s), 1+s]
  double gamma = 0;            // exponent log-uniform in [1/(1+g), 1+g]
  double channel_shuffle = 0;  // probability of permuting R, G and B
  double gray = 0;             // probability of a greyscale tuple
  bool any() const;
  void visit(ConfigVisitor& v);
};

// Applies `options` to every view of `sample` in place. The colour jitter is the same for every view, so views
// still agree on colour; each view's zoom moves its intrinsics; the mirror flips images, depth, intrinsics and
// poses together, so the tuple's geometry stays consistent. Same seed -> same result; all-zero options change
// nothing and draw nothing.
void augment_tuple(TupleSample& sample, const AugmentOptions& options, uint64_t seed);

}  // namespace isplat
