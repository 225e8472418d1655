# Which rosidl generators run. rosidl_default_generators runs every one
# registered in the ament index (C, C++, Python, and the C and C++ type
# supports). The Python bindings need only the C side, which halves the
# build; -DINTERFACES_CXX=ON adds the C++ headers and type supports for C++
# users. The type hashes do not depend on this choice: they come from the
# definitions alone (rosidl_generator_type_description).
option(INTERFACES_CXX "also generate the C++ headers and type supports" OFF)
if(INTERFACES_CXX)
  find_package(rosidl_default_generators REQUIRED)
else()
  find_package(rosidl_cmake REQUIRED)
  foreach(_generator
      rosidl_generator_type_description
      rosidl_generator_c
      rosidl_typesupport_introspection_c
      rosidl_typesupport_fastrtps_c
      rosidl_typesupport_c
      rosidl_generator_py)
    find_package(${_generator} REQUIRED)
  endforeach()
endif()
