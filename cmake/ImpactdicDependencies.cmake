# Every third-party dependency is found here and nowhere else. All come from Debian 12 packages
# (scripts/install_deps.sh installs them); the versions are the Debian 12 ones we build against.
# The libraries' own dependencies (also found by find_package(impactdic): the installed
# impactdicConfig.cmake reads the same list).
macro(impactdic_find_dependency name)
  find_package(${name} ${ARGN} REQUIRED)
endmacro()
include(ImpactdicLibraryDependencies)
find_package(CLI11 2.1 REQUIRED)
if(IMPACTDIC_BUILD_TESTS)
  find_package(GTest 1.12 REQUIRED)
  include(GoogleTest)
endif()
if(IMPACTDIC_BUILD_BENCHMARKS)
  find_package(benchmark 1.7 REQUIRED)
endif()
