# The layering check (docs/ARCHITECTURE.md): each module includes and links only the modules below
# it. Run as `cmake -DSOURCE_DIR=<tree> -DMODULES=<m1,m2,...> -P check_layering.cmake`, MODULES
# the build's FLOWSTEER_MODULES (tests/layering/CMakeLists.txt passes them); it prints every
# violation, as file:line or CMakeLists.txt and the module it reaches, and fails when there is
# one.

# What each module may use besides itself, lower floors first. Data flows camera -> flow ->
# features -> control -> drive: the stages (camera_io, servo, drivers) know only base, and the
# transports the camera and the drive may use (recording's ROS 2 messages, ros2_dds); pipeline
# joins camera and servo into the Brain; the simulator runs Brains in a rendered world and the
# evaluations measure its runs; the file readers, the robot's loop, the simulator in the loop
# and the command sit above.
set(allowed_base "")
set(allowed_report base)
set(allowed_recording base)
set(allowed_servo base)
set(allowed_ros2_dds base recording)
set(allowed_camera_io base recording ros2_dds)
set(allowed_drivers base recording ros2_dds)
set(allowed_calibration base camera_io)
set(allowed_sim_camera base camera_io servo)
set(allowed_pipeline base recording camera_io servo)
set(allowed_sim base report recording camera_io servo sim_camera pipeline)
set(allowed_eval base report recording camera_io servo sim_camera pipeline sim)
set(allowed_config base ros2_dds camera_io servo sim_camera drivers calibration)
set(allowed_robot base recording camera_io servo drivers calibration pipeline config)
set(allowed_sil base recording camera_io servo sim_camera drivers calibration pipeline sim config)
set(allowed_launch base report recording camera_io servo sim_camera drivers calibration pipeline sim eval config
    robot sil)

cmake_policy(VERSION 3.25)

if(NOT SOURCE_DIR OR NOT MODULES)
  message(FATAL_ERROR "check_layering: give -DSOURCE_DIR=<source tree> -DMODULES=<m1,m2,...>")
endif()
# The build's list of modules (FLOWSTEER_MODULES): a module it builds that the table above lacks
# is an error, not a module left unchecked.
string(REPLACE "," ";" modules "${MODULES}")
foreach(module IN LISTS modules)
  if(NOT DEFINED allowed_${module})
    message(FATAL_ERROR "check_layering: module ${module} has no row (allowed_${module}) in the table")
  endif()
endforeach()

set(violations 0)
foreach(module IN LISTS modules)
  set(ok ${module} ${allowed_${module}})
  file(GLOB_RECURSE sources "${SOURCE_DIR}/${module}/*.hpp" "${SOURCE_DIR}/${module}/*.cpp"
       "${SOURCE_DIR}/${module}/*.h")
  foreach(source IN LISTS sources)
    file(STRINGS "${source}" includes REGEX "^[ \t]*#[ \t]*include[ \t]*[\"<]flowsteer/")
    foreach(line IN LISTS includes)
      string(REGEX REPLACE ".*flowsteer/([a-z0-9_]+)/.*" "\\1" used "${line}")
      if(NOT used IN_LIST ok)
        file(RELATIVE_PATH where "${SOURCE_DIR}" "${source}")
        message("${where}: ${module} includes from ${used}: ${line}")
        math(EXPR violations "${violations} + 1")
      endif()
    endforeach()
  endforeach()
  set(cmake_file "${SOURCE_DIR}/${module}/CMakeLists.txt")
  if(EXISTS "${cmake_file}")
    file(READ "${cmake_file}" text)
    string(REGEX MATCHALL "flowsteer::[a-z0-9_]+" links "${text}")
    foreach(link IN LISTS links)
      string(REPLACE "flowsteer::" "" used "${link}")
      if(NOT used IN_LIST ok)
        message("${module}/CMakeLists.txt: ${module} links ${link}")
        math(EXPR violations "${violations} + 1")
      endif()
    endforeach()
  endif()
endforeach()

if(violations GREATER 0)
  message(FATAL_ERROR "check_layering: ${violations} violation(s) of the module layers")
endif()
message("check_layering: every module uses only the modules below it")
