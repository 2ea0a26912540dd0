// count_weight with an inverse divisor against the division transform does,
// bit for bit: on random weights, counts and divisors, and on divisors made
// so that the quotient falls next to a midpoint between two floats, where a
// plain multiplication rounds the other way.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>

#include "database/count_form.h"

namespace binbow::detail {
namespace {

std::uint32_t bits_of(float value) {
  std::uint32_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  return bits;
}

::testing::AssertionResult same_as_division(double word_weight, std::uint32_t count,
                                            double divisor) {
  const float divided = count_weight(word_weight, count, divisor);
  const float multiplied = count_weight(word_weight, count, divisor, inverse_divisor(divisor));
  if (bits_of(divided) == bits_of(multiplied)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << std::hexfloat << "word weight " << word_weight << ", count " << count << ", divisor "
         << divisor << ": " << multiplied << " instead of " << divided;
}

TEST(CountWeight, InverseGivesTheDivisionsWeightOnRandomInput) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<float> idf(0.01f, 20.0f);
  std::uniform_real_distribution<double> exponent(-40.0, 40.0);
  std::geometric_distribution<std::uint32_t> small_count(0.3);
  std::uniform_int_distribution<std::uint32_t> any_count(1, 65535);
  for (int i = 0; i < 2'000'000; ++i) {
    const bool wide = i % 4 == 0;  // weights and divisors over many binades
    const double word_weight = wide ? static_cast<float>(std::exp2(exponent(random))) : idf(random);
    const std::uint32_t count = i % 2 == 0 ? 1 + small_count(random) : any_count(random);
    const double divisor = wide ? std::exp2(exponent(random)) : 1.0 + 1e4 * idf(random);
    ASSERT_TRUE(same_as_division(word_weight, count, divisor));
  }
}

// The divisor is chosen so that word_weight × count / divisor is within a
// unit in the last place of a random midpoint between two floats.
TEST(CountWeight, InverseGivesTheDivisionsWeightNextToFloatMidpoints) {
  std::mt19937_64 random(11);
  std::uniform_real_distribution<float> idf(0.01f, 20.0f);
  std::uniform_real_distribution<float> target(1e-6f, 1.0f);
  std::uniform_int_distribution<std::uint32_t> any_count(1, 65535);
  int plain_multiplication_wrong = 0;
  for (int i = 0; i < 1'000'000; ++i) {
    const float below = target(random);
    const double midpoint =
        (static_cast<double>(below) + std::nextafter(below, INFINITY)) / 2;  // exact
    const double word_weight = idf(random);
    const std::uint32_t count = any_count(random);
    const double divisor = word_weight * count / midpoint;
    ASSERT_TRUE(same_as_division(word_weight, count, divisor));
    const auto plain = static_cast<float>(word_weight * count * inverse_divisor(divisor));
    if (bits_of(plain) != bits_of(count_weight(word_weight, count, divisor)))
      ++plain_multiplication_wrong;
  }
  // Otherwise this test would not show that the midpoints are handled.
  EXPECT_GT(plain_multiplication_wrong, 0);
}

TEST(CountWeight, ExactMidpointsRoundToEvenAsTheDivisionDoes) {
  const double odd_last_bit = 1.0 + 0x1p-23;  // a float; × 3 is a midpoint
  for (double divisor : {1.0, 2.0, 0.5, 0x1p-20, 0x1p20})
    for (std::uint32_t count : {3u, 5u, 7u, 65535u})
      EXPECT_TRUE(same_as_division(odd_last_bit, count, divisor));
}

TEST(CountWeight, TinyAndMissingDivisorsFallBackToTheDivision) {
  EXPECT_TRUE(same_as_division(0x1p-140, 1, 1.0));  // a subnormal float
  EXPECT_TRUE(same_as_division(1.0, 1, 0x1p200));
  EXPECT_TRUE(same_as_division(0.0, 1, 3.0));
  EXPECT_EQ(inverse_divisor(0.0), 0.0);
  const double zero = 0.0;
  EXPECT_EQ(count_weight(1.0, 1, zero, inverse_divisor(zero)), count_weight(1.0, 1, zero));
}

}  // namespace
}  // namespace binbow::detail
