# CMake helpers of tabletop_common, available to every package that finds it through catkin.
#
# tabletop_ros_free_core(<target>)
#   Makes "this core library is ROS-free" a property the build checks, not a convention:
#   - its sources see a poisoned copy of the ROS include tree first: every header of the ROS
#     packages below (ros/, nodelet/, the message packages, tabletop_msgs' messages, ...) is
#     replaced by one that stops the compilation with an #error naming the target;
#   - a shared library must resolve every symbol at link time (-Wl,--no-undefined), so one that
#     calls into a ROS library it does not link fails to link.
#   Debian installs ROS headers in /usr/include beside Eigen and OpenCV, so leaving ROS out of
#   the include path alone would not stop them.

set(TABLETOP_ROS_POISON_DIR "${CMAKE_BINARY_DIR}/tabletop_ros_poison" CACHE INTERNAL
  "include directory with an #error header for every ROS header")
# ROS packages whose headers a core must not include (their include folder names).
set(TABLETOP_ROS_HEADER_DIRS ros rosbag rosbag_storage nodelet pluginlib class_loader
  diagnostic_updater diagnostic_msgs dynamic_reconfigure message_filters image_transport
  cv_bridge tf2_ros tf2_msgs tf2 std_msgs std_srvs sensor_msgs geometry_msgs
  visualization_msgs rosgraph_msgs actionlib_msgs xmlrpcpp)

function(_tabletop_write_ros_poison)
  find_path(_ros_root ros/time.h)
  set(_headers "")
  if(_ros_root)
    foreach(dir ${TABLETOP_ROS_HEADER_DIRS})
      if(IS_DIRECTORY "${_ros_root}/${dir}")
        file(GLOB_RECURSE _found RELATIVE "${_ros_root}" "${_ros_root}/${dir}/*.h"
          "${_ros_root}/${dir}/*.hpp")
        list(APPEND _headers ${_found})
      endif()
    endforeach()
  endif()
  # The project's own messages (generated at build time, so named from the .msg files).
  if(DEFINED tabletop_msgs_SOURCE_DIR)
    file(GLOB _msgs RELATIVE "${tabletop_msgs_SOURCE_DIR}/msg" "${tabletop_msgs_SOURCE_DIR}/msg/*.msg")
  elseif(DEFINED tabletop_msgs_SOURCE_PREFIX)
    file(GLOB _msgs RELATIVE "${tabletop_msgs_SOURCE_PREFIX}/msg" "${tabletop_msgs_SOURCE_PREFIX}/msg/*.msg")
  else()
    set(_msgs BodyPose.msg HandMesh.msg HandMeshes.msg HandVolumes.msg MultiViewFrame.msg
      TrackedTarget.msg TrackedTargets.msg VoxelVolume.msg)
  endif()
  foreach(m ${_msgs})
    string(REGEX REPLACE "\\.msg$" ".h" _h "${m}")
    list(APPEND _headers "tabletop_msgs/${_h}")
  endforeach()
  foreach(h ${_headers})
    set(_file "${TABLETOP_ROS_POISON_DIR}/${h}")
    if(NOT EXISTS "${_file}")
      file(WRITE "${_file}"
        "#error \"${h} is a ROS header: a ROS-free core library (tabletop_ros_free_core in its CMakeLists.txt) must not include it; move the code to src/ros/\"\n")
    endif()
  endforeach()
  # Each call adds what is new (tabletop_msgs' list is known once that package is configured).
  list(LENGTH _headers _n)
  if(_n LESS 50)
    message(WARNING "tabletop_common: only ${_n} ROS headers found to guard the core libraries "
      "against (ros/time.h found in '${_ros_root}')")
  endif()
endfunction()

function(tabletop_ros_free_core target)
  _tabletop_write_ros_poison()
  target_include_directories(${target} BEFORE PRIVATE "${TABLETOP_ROS_POISON_DIR}")
  get_target_property(_type ${target} TYPE)
  if(_type STREQUAL "SHARED_LIBRARY" OR _type STREQUAL "MODULE_LIBRARY")
    target_link_options(${target} PRIVATE -Wl,--no-undefined)
  endif()
endfunction()

# tabletop_package_dir(<package> <variable>)
#   The source folder of another package of this workspace (for test data such as its config
#   files), in one CMake project (catkin_make) and in isolated builds alike, instead of paths
#   like ../other_package that only hold in one source layout.
function(tabletop_package_dir pkg var)
  if(DEFINED ${pkg}_SOURCE_DIR)
    set(${var} "${${pkg}_SOURCE_DIR}" PARENT_SCOPE)
  elseif(DEFINED ${pkg}_SOURCE_PREFIX)
    set(${var} "${${pkg}_SOURCE_PREFIX}" PARENT_SCOPE)
  elseif(DEFINED ${pkg}_DIR)
    # installed: <prefix>/share/<pkg>/cmake -> <prefix>/share/<pkg>
    get_filename_component(_share "${${pkg}_DIR}/.." ABSOLUTE)
    set(${var} "${_share}" PARENT_SCOPE)
  else()
    message(FATAL_ERROR "tabletop_package_dir: package ${pkg} not found (find it through catkin first)")
  endif()
endfunction()

# tabletop_find_cuda()
#   The CUDA backends (issue 20) are built only where nvcc is found: CUDACXX, nvcc on PATH, or
#   /usr/local/cuda/bin/nvcc; -DTABLETOP_CUDA=OFF leaves them out. Sets TABLETOP_HAVE_CUDA in the
#   caller's scope and, when ON, enables the CUDA language for sm_75 (Turing and later) and sm_90
#   (H100/H200) unless CMAKE_CUDA_ARCHITECTURES says otherwise. A build without nvcc compiles
#   stubs that report "not compiled in", and every path runs on the CPU.
macro(tabletop_find_cuda)
  option(TABLETOP_CUDA "Build the CUDA backends where nvcc is found" ON)
  set(TABLETOP_HAVE_CUDA OFF)
  if(TABLETOP_CUDA)
    if(NOT CMAKE_CUDA_COMPILER AND NOT DEFINED ENV{CUDACXX} AND EXISTS /usr/local/cuda/bin/nvcc)
      set(CMAKE_CUDA_COMPILER /usr/local/cuda/bin/nvcc CACHE FILEPATH "CUDA compiler")
    endif()
    include(CheckLanguage)
    check_language(CUDA)
    if(CMAKE_CUDA_COMPILER)
      if(NOT CMAKE_CUDA_ARCHITECTURES)
        set(CMAKE_CUDA_ARCHITECTURES 75 90)
      endif()
      enable_language(CUDA)
      find_package(CUDAToolkit QUIET)
      if(CUDAToolkit_FOUND)
        set(TABLETOP_HAVE_CUDA ON)
      endif()
    endif()
  endif()
  if(TABLETOP_HAVE_CUDA)
    message(STATUS "${PROJECT_NAME}: CUDA backend with ${CMAKE_CUDA_COMPILER} (CUDA ${CUDAToolkit_VERSION}), architectures ${CMAKE_CUDA_ARCHITECTURES}")
  else()
    message(STATUS "${PROJECT_NAME}: no CUDA backend (TABLETOP_CUDA=${TABLETOP_CUDA}, nvcc not found or disabled); CPU paths only")
  endif()
endmacro()

# tabletop_cuda_library(<target> <sources>...)
#   A static, position-independent CUDA library (linked privately into a package's core shared
#   library). Arithmetic is IEEE as on the CPU: no FMA contraction (--fmad=false; the shared
#   __host__ __device__ functions use fmaf explicitly where the CPU uses std::fma), precise
#   division and square root, so GPU and CPU give the same bytes.
function(tabletop_cuda_library target)
  add_library(${target} STATIC ${ARGN})
  set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON CUDA_STANDARD 17
    CUDA_STANDARD_REQUIRED ON)
  target_compile_options(${target} PRIVATE $<$<COMPILE_LANGUAGE:CUDA>:--fmad=false
    -prec-div=true -prec-sqrt=true --expt-relaxed-constexpr -Xcompiler=-fPIC>)
  target_link_libraries(${target} PUBLIC CUDA::cudart_static)
endfunction()
