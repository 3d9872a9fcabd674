// The IC-GN kernel for the compiler's baseline instruction set, compiled with its own flags
// (src/dic/CMakeLists.txt).
#define IMPACTDIC_DIC_KERNEL_NS scalar
#define IMPACTDIC_DIC_KERNEL_LEVEL 0
#include "icgn_kernel_body.h"
