# Every third-party dependency is found here and nowhere else. All come from Debian 12 packages
# (scripts/install_deps.sh installs them); the versions are the Debian 12 ones we build against.
find_package(Threads REQUIRED)
find_package(OpenCV 4.6 REQUIRED COMPONENTS core imgproc imgcodecs videoio calib3d)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(HDF5 1.10 REQUIRED COMPONENTS C CXX)
find_package(TBB 2021 REQUIRED)
find_package(CLI11 2.1 REQUIRED)
find_package(yaml-cpp 0.7 REQUIRED)
find_package(fmt 9 REQUIRED)
find_package(spdlog 1.10 REQUIRED)
if(IMPACTDIC_BUILD_TESTS)
  find_package(GTest 1.12 REQUIRED)
  include(GoogleTest)
endif()
if(IMPACTDIC_BUILD_BENCHMARKS)
  find_package(benchmark 1.7 REQUIRED)
endif()

find_package(ZLIB 1.2 REQUIRED)

# Imported targets for the packages whose Debian config files do not provide one.
# OpenCV by component, so that the binary loads only what it needs at start-up: core and imgproc
# everywhere, calib3d where cameras are calibrated. imgcodecs and videoio (with GDAL, GDCM,
# FFmpeg, GStreamer: ~230 shared libraries, ~0.09 s of dynamic loading per process) only in the
# two plugins that src/io loads on first use (io/opencv_codecs.h), and in tests and benchmarks.
if(NOT TARGET impactdic_deps::opencv)
  add_library(impactdic_deps::opencv INTERFACE IMPORTED)
  target_include_directories(impactdic_deps::opencv SYSTEM INTERFACE ${OpenCV_INCLUDE_DIRS})
  target_link_libraries(impactdic_deps::opencv INTERFACE opencv_core opencv_imgproc)
  add_library(impactdic_deps::opencv_calib3d INTERFACE IMPORTED)
  target_link_libraries(impactdic_deps::opencv_calib3d INTERFACE impactdic_deps::opencv
                                                                 opencv_calib3d)
  add_library(impactdic_deps::opencv_imgcodecs INTERFACE IMPORTED)
  target_link_libraries(impactdic_deps::opencv_imgcodecs INTERFACE impactdic_deps::opencv
                                                                   opencv_imgcodecs)
  add_library(impactdic_deps::opencv_videoio INTERFACE IMPORTED)
  target_link_libraries(impactdic_deps::opencv_videoio INTERFACE impactdic_deps::opencv
                                                                 opencv_videoio)
  add_library(impactdic_deps::opencv_codecs INTERFACE IMPORTED)
  target_link_libraries(impactdic_deps::opencv_codecs INTERFACE impactdic_deps::opencv_imgcodecs
                                                                impactdic_deps::opencv_videoio)
endif()
if(NOT TARGET impactdic_deps::hdf5)
  add_library(impactdic_deps::hdf5 INTERFACE IMPORTED)
  target_include_directories(impactdic_deps::hdf5 SYSTEM INTERFACE ${HDF5_INCLUDE_DIRS})
  target_link_libraries(impactdic_deps::hdf5 INTERFACE ${HDF5_LIBRARIES})
  target_compile_definitions(impactdic_deps::hdf5 INTERFACE ${HDF5_DEFINITIONS})
endif()
if(TARGET yaml-cpp AND NOT TARGET yaml-cpp::yaml-cpp)
  add_library(yaml-cpp::yaml-cpp ALIAS yaml-cpp)
endif()
