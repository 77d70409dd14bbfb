# snapnav_lcmgen(<target> PACKAGE <pkg> FILES <a.lcm> ...)
#
# Runs lcm-gen into the build folder (never into the source tree):
#  - C++ headers in ${CMAKE_BINARY_DIR}/lcmtypes/include/<pkg>/<struct>.hpp,
#    exposed through the INTERFACE library <target>;
#  - if a JDK and lcm.jar are found, Java classes compiled into
#    ${CMAKE_BINARY_DIR}/share/java/lcmtypes_<pkg>.jar (target <target>_java),
#    so that lcm-spy can decode every type.
# The struct name is taken from the file name <pkg>_<struct>.lcm.
#
# The generated C++ decoders of LCM 1.3.1 resize arrays to the count read from
# the wire before checking it against the payload length, so a corrupt count
# (2^31) allocates gigabytes; HardenLcmDecoders.cmake adds that check.
function(snapnav_lcmgen target)
  cmake_parse_arguments(ARG "" "PACKAGE" "FILES" ${ARGN})
  set(inc_dir ${CMAKE_BINARY_DIR}/lcmtypes/include)
  set(java_dir ${CMAKE_BINARY_DIR}/lcmtypes/java)
  set(headers)
  set(java_sources)
  set(lcm_files)
  foreach(f ${ARG_FILES})
    get_filename_component(abs ${f} ABSOLUTE)
    get_filename_component(stem ${f} NAME_WE)
    string(REGEX REPLACE "^${ARG_PACKAGE}_" "" struct ${stem})
    list(APPEND lcm_files ${abs})
    list(APPEND headers ${inc_dir}/${ARG_PACKAGE}/${struct}.hpp)
    list(APPEND java_sources ${java_dir}/${ARG_PACKAGE}/${struct}.java)
  endforeach()

  add_custom_command(
    OUTPUT ${headers}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${inc_dir}
    COMMAND ${LCM_GEN_EXECUTABLE} --cpp --cpp-std c++11 --cpp-hpath ${inc_dir} ${lcm_files}
    COMMAND ${CMAKE_COMMAND} -DDIR=${inc_dir}/${ARG_PACKAGE} -P ${PROJECT_SOURCE_DIR}/cmake/HardenLcmDecoders.cmake
    DEPENDS ${lcm_files} ${PROJECT_SOURCE_DIR}/cmake/HardenLcmDecoders.cmake
    COMMENT "lcm-gen (C++) for ${ARG_PACKAGE}"
    VERBATIM)
  add_custom_target(${target}_gen DEPENDS ${headers})
  add_library(${target} INTERFACE)
  add_dependencies(${target} ${target}_gen)
  target_include_directories(${target} INTERFACE ${inc_dir})
  target_link_libraries(${target} INTERFACE PkgConfig::LCM)

  if(Java_JAVAC_EXECUTABLE AND Java_JAR_EXECUTABLE AND LCM_JAR)
    set(jar ${CMAKE_BINARY_DIR}/share/java/lcmtypes_${ARG_PACKAGE}.jar)
    set(classes ${CMAKE_BINARY_DIR}/lcmtypes/classes)
    add_custom_command(
      OUTPUT ${jar}
      COMMAND ${CMAKE_COMMAND} -E rm -rf ${java_dir} ${classes}
      COMMAND ${CMAKE_COMMAND} -E make_directory ${java_dir} ${classes} ${CMAKE_BINARY_DIR}/share/java
      COMMAND ${LCM_GEN_EXECUTABLE} --java --jpath ${java_dir} ${lcm_files}
      COMMAND ${Java_JAVAC_EXECUTABLE} -nowarn -source 8 -target 8 -cp ${LCM_JAR} -d ${classes} ${java_sources}
      COMMAND ${Java_JAR_EXECUTABLE} cf ${jar} -C ${classes} .
      DEPENDS ${lcm_files}
      COMMENT "lcm-gen (Java) and jar for ${ARG_PACKAGE}"
      VERBATIM)
    add_custom_target(${target}_java ALL DEPENDS ${jar})
    set_property(GLOBAL PROPERTY SNAPNAV_LCMTYPES_JAR ${jar})
  else()
    message(WARNING "No JDK or lcm.jar found: lcm-spy will not decode snapnav types "
                    "(install default-jdk-headless and liblcm-java).")
  endif()
endfunction()
