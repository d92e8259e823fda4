// The C API compiled into the test executable (SPARSEBODY_C_STATIC), with the flags of the C++
// pipelines it is compared with, so the comparison can be bit for bit.
#include "sparsebody/c/sparsebody_c_impl.hpp"
