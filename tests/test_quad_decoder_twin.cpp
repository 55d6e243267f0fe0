// quad_decoder twin alone: the property suite (tests/quad_properties.hpp) at
// the default widths and at small widths where every counter saturates.
#include <gtest/gtest.h>

#include "quad_properties.hpp"

namespace mc::test {
namespace {

using TwinSims = ::testing::Types<QuadTwinSimT<QuadDefault>, QuadTwinSimT<QuadSmall>>;
INSTANTIATE_TYPED_TEST_SUITE_P(Twin, QuadProperties, TwinSims);

}  // namespace
}  // namespace mc::test
