// The include name "Thirdparty/DBoW2/DUtils/Random.h" of ORB-SLAM's copy of
// DBoW2, whose RANSAC loops (Initializer, PnPsolver, Sim3Solver,
// TwoViewReconstruction) draw their samples with DUtils::Random. The same
// functions with the same results: the C library's rand() and srand(), so
// that SeedRandOnce(0) followed by RandomInt(...) gives the numbers the
// copy gives, and RandomInt maps rand() onto [min, max] the way it does.
// Header-only. The copy's UnrepeatedRandomizer is not provided (ORB-SLAM
// does not use it). Only under this ORB-SLAM name: DLib, which DLoopDetector
// users have installed, owns <DUtils/Random.h>. Found through the opt-in
// target binbow::dbow2_names (pkg-config binbow-dbow2-names).
#ifndef BINBOW_COMPAT_NAMES_ORBSLAM_DUTILS_RANDOM_H
#define BINBOW_COMPAT_NAMES_ORBSLAM_DUTILS_RANDOM_H

#include <cmath>
#include <cstdlib>
#include <ctime>

namespace DUtils {

/// Pseudo-random numbers from the C library's generator.
class Random {
 public:
  /// Seeds rand() from the clock (whole seconds).
  static void SeedRand() { std::srand(static_cast<unsigned>(std::time(0))); }
  /// SeedRand() unless SeedRandOnce() or SeedRandOnce(int) seeded before.
  static void SeedRandOnce() {
    if (!already_seeded()) {
      SeedRand();
      already_seeded() = true;
    }
  }
  /// Seeds rand() with `seed`.
  static void SeedRand(int seed) { std::srand(static_cast<unsigned>(seed)); }
  /// SeedRand(seed) unless SeedRandOnce() or SeedRandOnce(int) seeded before.
  static void SeedRandOnce(int seed) {
    if (!already_seeded()) {
      SeedRand(seed);
      already_seeded() = true;
    }
  }

  /// rand() / RAND_MAX in T: a value in [0, 1].
  template <class T>
  static T RandomValue() {
    return static_cast<T>(std::rand()) / static_cast<T>(RAND_MAX);
  }
  /// A value in [min, max].
  template <class T>
  static T RandomValue(T min, T max) {
    return RandomValue<T>() * (max - min) + min;
  }
  /// An integer in [min, max], both included, from one rand().
  static int RandomInt(int min, int max) {
    const int d = max - min + 1;
    return static_cast<int>(
               (static_cast<double>(std::rand()) / (static_cast<double>(RAND_MAX) + 1.0)) * d) +
           min;
  }
  /// A normally distributed value (Box-Muller's polar form over RandomValue).
  template <class T>
  static T RandomGaussianValue(T mean, T sigma) {
    T x1, x2, w;
    do {
      x1 = static_cast<T>(2) * RandomValue<T>() - static_cast<T>(1);
      x2 = static_cast<T>(2) * RandomValue<T>() - static_cast<T>(1);
      w = x1 * x1 + x2 * x2;
    } while (w >= static_cast<T>(1) || w == static_cast<T>(0));
    w = std::sqrt((static_cast<T>(-2) * std::log(w)) / w);
    return mean + x1 * w * sigma;
  }

 private:
  // One flag for the whole program, as the copy's static member (an inline
  // function's static: this header has no source file to define it in).
  static bool& already_seeded() {
    static bool seeded = false;
    return seeded;
  }
};

}  // namespace DUtils

#endif
