# The Python module installed (ctest `python_install`, label python): installs the build tree
# BUILD_DIR into a fresh prefix under WORK_DIR and, from WORK_DIR (no build tree on the path),
# imports the package with PYTHONPATH=PREFIX/lib/python3/dist-packages as docs/python.md says, and
# correlates a pair with it. Fails at the first step that fails, with that step's output.
#   cmake -DBUILD_DIR=... -DWORK_DIR=... -DPYTHON=/usr/bin/python3 -DINSTALL_DIR=lib/python3/...
#         -P run_install_test.cmake
foreach(var BUILD_DIR WORK_DIR PYTHON INSTALL_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_install_test.cmake: -D${var}=... is required")
  endif()
endforeach()

function(step what)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE code
                  OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "python install test: ${what} failed (${code}):\n${out}")
  endif()
  message(STATUS "python install test: ${what}: done\n${out}")
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
step("install into ${prefix}" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
set(script [=[
import os, sys
import numpy as np
import impactdic
prefix = sys.argv[1]
assert impactdic.__file__.startswith(prefix), impactdic.__file__
for variable in ("IMPACTDIC_OPENCV_CODECS", "IMPACTDIC_OPENCV_VIDEO"):
    assert os.environ[variable].startswith(prefix), (variable, os.environ[variable])
    assert os.path.exists(os.environ[variable]), os.environ[variable]
rng = np.random.default_rng(2)
k = np.fft.fftfreq(96)
spectrum = np.fft.fft2(rng.random((96, 96))) * np.exp(-4.5 * np.pi**2 * (k[:, None]**2 + k**2))
moved = spectrum * np.exp(-2j * np.pi * k * 0.5)
ref, cur = (np.uint8(np.clip(128 + 600 * (np.fft.ifft2(s).real - 0.5), 0, 255))
            for s in (spectrum, moved))
r = impactdic.correlate(ref, cur, dic={"subset_size": 21, "step": 16})
u = np.median(r.u[1][r.valid[1]])
assert abs(u - 0.5) < 0.02, u
print(f"impactdic {impactdic.__version__} from {impactdic.__file__}: u = {u:.3f} px")
]=])
file(WRITE ${WORK_DIR}/check.py "${script}")
step("import and correlate"
     ${CMAKE_COMMAND} -E env --unset=IMPACTDIC_OPENCV_CODECS --unset=IMPACTDIC_OPENCV_VIDEO
     PYTHONPATH=${prefix}/${INSTALL_DIR} ${PYTHON} ${WORK_DIR}/check.py ${prefix})
