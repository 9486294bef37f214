// The test executable finds the synthgen-reader this build made (it lives next to the
// Python module, not next to the tests), unless SYNTHGEN_READER says otherwise.
#include <cstdlib>

namespace {
const int k_reader = setenv("SYNTHGEN_READER", SYNTHGEN_READER_PATH, 0);
}  // namespace
