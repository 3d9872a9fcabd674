# The dependencies of the impactdic libraries, with the versions we build against (Debian 12),
# and the imported targets of ours that the libraries link. Read by the build
# (ImpactdicDependencies.cmake) and by an installed package's impactdicConfig.cmake, each with its
# own impactdic_find_dependency(NAME [VERSION] [ARGS...]) (find_package REQUIRED, or
# find_dependency).
impactdic_find_dependency(Threads)
# aruco (ChArUco boards) is a contrib module: Debian's libopencv-contrib-dev.
impactdic_find_dependency(OpenCV 4.6 COMPONENTS core imgproc imgcodecs videoio calib3d aruco)
impactdic_find_dependency(Eigen3 3.4 NO_MODULE)
# HDF5's C++ API (it links the C library); FindHDF5 tries its C component only where the project
# enabled C (a consumer's C++-only project need not).
get_property(impactdic_languages GLOBAL PROPERTY ENABLED_LANGUAGES)
if("C" IN_LIST impactdic_languages)
  impactdic_find_dependency(HDF5 1.10 COMPONENTS C CXX)
else()
  impactdic_find_dependency(HDF5 1.10 COMPONENTS CXX)
endif()
impactdic_find_dependency(TBB 2021)
impactdic_find_dependency(yaml-cpp 0.7)
impactdic_find_dependency(fmt 9)
impactdic_find_dependency(spdlog 1.10)
impactdic_find_dependency(ZLIB 1.2)

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
  add_library(impactdic_deps::opencv_aruco INTERFACE IMPORTED)
  target_link_libraries(impactdic_deps::opencv_aruco INTERFACE impactdic_deps::opencv_calib3d
                                                               opencv_aruco)
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
# HDF5: the shared libraries, or, for a target whose property IMPACTDIC_STATIC_HDF5 is true (the
# command-line tool), Debian's static archives of the same version with zlib and szip. Debian's
# shared libhdf5 loads libcurl and libcrypto (its remote-file driver, which we do not use) and
# their ~30 libraries: ~4 ms of dynamic loading in every process. The static archives need
# neither. Where they are missing, every target links the shared libraries.
if(NOT TARGET impactdic_deps::hdf5)
  add_library(impactdic_deps::hdf5 INTERFACE IMPORTED)
  target_include_directories(impactdic_deps::hdf5 SYSTEM INTERFACE ${HDF5_INCLUDE_DIRS})
  target_compile_definitions(impactdic_deps::hdf5 INTERFACE ${HDF5_DEFINITIONS})
  set(impactdic_hdf5_static "")
  foreach(shared IN ITEMS "${HDF5_CXX_LIBRARY_hdf5_cpp}" "${HDF5_C_LIBRARY_hdf5}")
    string(REGEX REPLACE "\\.so$" ".a" archive "${shared}")
    if(shared MATCHES "\\.so$" AND EXISTS "${archive}")
      list(APPEND impactdic_hdf5_static "${archive}")
    else()
      set(impactdic_hdf5_static "")
      break()
    endif()
  endforeach()
  find_library(IMPACTDIC_SZIP_LIBRARY NAMES sz)
  if(impactdic_hdf5_static AND IMPACTDIC_SZIP_LIBRARY)
    set(static_hdf5 "$<BOOL:$<TARGET_PROPERTY:IMPACTDIC_STATIC_HDF5>>")
    foreach(lib IN LISTS HDF5_LIBRARIES)
      target_link_libraries(impactdic_deps::hdf5 INTERFACE "$<$<NOT:${static_hdf5}>:${lib}>")
    endforeach()
    foreach(lib IN LISTS impactdic_hdf5_static ITEMS "${IMPACTDIC_SZIP_LIBRARY}" ZLIB::ZLIB
                         ${CMAKE_DL_LIBS} m)
      target_link_libraries(impactdic_deps::hdf5 INTERFACE "$<${static_hdf5}:${lib}>")
    endforeach()
  else()
    target_link_libraries(impactdic_deps::hdf5 INTERFACE ${HDF5_LIBRARIES})
  endif()
endif()
if(TARGET yaml-cpp AND NOT TARGET yaml-cpp::yaml-cpp)
  add_library(yaml-cpp::yaml-cpp ALIAS yaml-cpp)
endif()
