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
# The Python module (src/python, docs/python.md): Python 3.11's development files (python3-dev)
# and pybind11 2.10 (pybind11-dev). Optional: IMPACTDIC_PYTHON defaults to ON when both are found.
# Python3 is found first so that pybind11 uses CMake's FindPython.
# Debian's /usr/bin/python3 (its python3-numpy is what the module and its tests use) unless
# -DPython3_EXECUTABLE=... names another: a python3 earlier in PATH (pyenv, a venv) is not taken.
if(NOT Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(Python3_EXECUTABLE /usr/bin/python3)
endif()
find_package(Python3 3.9 COMPONENTS Interpreter Development.Module)
if(Python3_FOUND)
  find_package(pybind11 2.10 CONFIG QUIET)
endif()
