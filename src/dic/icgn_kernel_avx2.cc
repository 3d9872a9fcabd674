// The IC-GN kernel for AVX2 + FMA, compiled with its own flags (src/dic/CMakeLists.txt).
#define IMPACTDIC_DIC_KERNEL_NS avx2
#define IMPACTDIC_DIC_KERNEL_LEVEL 1
#include "icgn_kernel_body.h"
