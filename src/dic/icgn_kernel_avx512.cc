// The IC-GN kernel for AVX-512 (F, DQ), compiled with its own flags (src/dic/CMakeLists.txt).
#define IMPACTDIC_DIC_KERNEL_NS avx512
#define IMPACTDIC_DIC_KERNEL_LEVEL 2
#include "icgn_kernel_body.h"
