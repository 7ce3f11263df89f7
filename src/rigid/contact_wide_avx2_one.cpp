// Rigid bodies: the contact kernels' AVX2 path over one-point blocks (contact_wide.h), in a file of its own
// so that the build compiles it beside the other paths and block kinds.
#include "contact_wide.h"

namespace pba::detail {

#if PBA_RIGID_HAVE_X86
PBA_CONTACT_PATH(, avx2, OnePointBlock, OnePointAnchors);
#endif

}  // namespace pba::detail
