# Injected by scripts/setup.sh (-DCMAKE_PROJECT_INCLUDE=<this file>) when
# msg_defs/ is built against the ros-jazzy-* PyPI wheels. Not used, and not
# needed, in an ordinary ROS 2 workspace (colcon build): msg_defs/ itself stays
# a plain ament_cmake package.
#
# Problem: rosidl_generator_py (Jazzy) declares
#   target_include_directories(<pkg>__rosidl_generator_py PUBLIC
#       ${Python3_INCLUDE_DIRS} ${Python3_NumPy_INCLUDE_DIRS})
# so the ABSOLUTE Python and NumPy include dirs of the machine that built each
# message wheel are baked into its exported target, e.g. in
#   <venv>/share/std_msgs/cmake/export_std_msgs__rosidl_generator_pyExport.cmake
#   INTERFACE_INCLUDE_DIRECTORIES
#     "/opt/python/cp311-cp311/include/python3.11;
#      /opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include"
# (/opt/python/cp311-cp311 is the manylinux build image's CPython). Our
# brake_sim_msgs__rosidl_generator_py links those targets, and CMake's generate
# step rejects an imported target whose include dir does not exist
# ("Imported target ... includes non-existent path").
#
# Fix: at the end of the configure step (deferred, so every imported target
# already exists) replace, in the imported targets of this directory, each
# NON-EXISTENT include dir that is a CPython header dir (.../include/python3.N)
# by this build's Python3_INCLUDE_DIRS, and each non-existent NumPy header dir
# (.../numpy/_core/include or .../numpy/core/include) by this build's
# Python3_NumPy_INCLUDE_DIRS -- exactly what rosidl_generator_py itself uses for
# our own target. Anything else that does not exist is left alone, so real
# packaging errors still fail the build. The installed wheels are not modified.
#
# Requires CMake >= 3.21 (cmake_language(DEFER), IMPORTED_TARGETS).

cmake_minimum_required(VERSION 3.21)

function(_brake_sim_fix_wheel_python_includes)
  get_directory_property(_targets IMPORTED_TARGETS)

  # Python3_* come from find_package(Python3 ... Development.Module NumPy) done
  # by rosidl_generator_py (a macro, so they are visible here). Find them
  # ourselves if not (e.g. a package without Python generation).
  if(NOT Python3_INCLUDE_DIRS OR NOT Python3_NumPy_INCLUDE_DIRS)
    find_package(Python3 QUIET COMPONENTS Interpreter Development.Module NumPy)
  endif()

  set(_n_fixed 0)
  foreach(_tgt IN LISTS _targets)
    get_target_property(_dirs ${_tgt} INTERFACE_INCLUDE_DIRECTORIES)
    if(NOT _dirs)
      continue()
    endif()
    set(_new_dirs "")
    set(_changed FALSE)
    foreach(_dir IN LISTS _dirs)
      if(_dir MATCHES "^\\$<" OR EXISTS "${_dir}")
        list(APPEND _new_dirs "${_dir}")
      elseif(_dir MATCHES "/include/python3\\.[0-9]+t?$" AND Python3_INCLUDE_DIRS)
        list(APPEND _new_dirs ${Python3_INCLUDE_DIRS})
        set(_changed TRUE)
      elseif(_dir MATCHES "/numpy/(_core|core)/include$" AND Python3_NumPy_INCLUDE_DIRS)
        list(APPEND _new_dirs ${Python3_NumPy_INCLUDE_DIRS})
        set(_changed TRUE)
      else()
        list(APPEND _new_dirs "${_dir}")
      endif()
    endforeach()
    if(_changed)
      list(REMOVE_DUPLICATES _new_dirs)
      set_target_properties(${_tgt} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_new_dirs}")
      math(EXPR _n_fixed "${_n_fixed} + 1")
    endif()
  endforeach()
  if(_n_fixed GREATER 0)
    message(STATUS "ros-wheels fix: pointed ${_n_fixed} imported target(s) from the wheel "
      "build machine's Python/NumPy include dirs to ${Python3_INCLUDE_DIRS};"
      "${Python3_NumPy_INCLUDE_DIRS}")
  endif()
endfunction()

# Included after every project() call: defer once per directory.
get_directory_property(_brake_sim_fix_deferred _BRAKE_SIM_FIX_DEFERRED)
if(NOT _brake_sim_fix_deferred)
  set_directory_properties(PROPERTIES _BRAKE_SIM_FIX_DEFERRED TRUE)
  cmake_language(DEFER CALL _brake_sim_fix_wheel_python_includes)
endif()
unset(_brake_sim_fix_deferred)
