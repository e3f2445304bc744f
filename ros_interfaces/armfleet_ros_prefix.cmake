# Shared by the interface packages here: build against the ROS 2 packages installed from
# the package index into this Python environment (its prefix holds share/, lib/, include/).

# The Python that runs the build (scikit-build-core names it) and its environment's prefix.
find_package(Python3 REQUIRED COMPONENTS Interpreter)
execute_process(
  COMMAND "${Python3_EXECUTABLE}" -c "import sys; print(sys.prefix)"
  OUTPUT_VARIABLE ARMFLEET_ROS_PREFIX
  OUTPUT_STRIP_TRAILING_WHITESPACE
  COMMAND_ERROR_IS_FATAL ANY)
list(PREPEND CMAKE_PREFIX_PATH "${ARMFLEET_ROS_PREFIX}")
set(ENV{AMENT_PREFIX_PATH} "${ARMFLEET_ROS_PREFIX}")
set(PYTHON_EXECUTABLE "${Python3_EXECUTABLE}")

# The index's ROS wheels were built in manylinux containers and export their Python
# include folder there (/opt/python/...), which no other machine has; CMake refuses to
# generate with a missing path. Called after rosidl_generate_interfaces (which finds
# more packages), it drops those paths: the Python targets find this interpreter's own.
function(armfleet_drop_build_machine_paths)
  get_property(imported DIRECTORY PROPERTY IMPORTED_TARGETS)
  foreach(target IN LISTS imported)
    get_target_property(dirs ${target} INTERFACE_INCLUDE_DIRECTORIES)
    if(dirs)
      list(FILTER dirs EXCLUDE REGEX "^/opt/python/")
      set_target_properties(${target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${dirs}")
    endif()
  endforeach()
endfunction()
