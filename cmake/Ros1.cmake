# Debian's ROS1 libraries (librosbag-storage-dev, libroscpp-dev, libsensor-msgs-dev).
# Their CMake configs pull pluginlib/ament and run Python helpers that break under a
# non-system python3, and rosbag_storage.pc names a pluginlib.pc Debian does not ship,
# so we locate the few libraries we link directly. Headers live in /usr/include.
set(_mmlio_ros_libs rosbag_storage roscpp_serialization rostime cpp_common roslz4 console_bridge class_loader)
set(_mmlio_ros_paths "")
foreach(lib ${_mmlio_ros_libs})
  find_library(MMLIO_ROS_${lib} NAMES ${lib})
  if(NOT MMLIO_ROS_${lib})
    message(FATAL_ERROR "ROS1 library '${lib}' not found: run scripts/install-deps.sh")
  endif()
  list(APPEND _mmlio_ros_paths ${MMLIO_ROS_${lib}})
endforeach()
find_path(MMLIO_ROS_INCLUDE rosbag/bag.h)
find_path(MMLIO_SENSOR_MSGS_INCLUDE sensor_msgs/PointCloud2.h)
if(NOT MMLIO_ROS_INCLUDE OR NOT MMLIO_SENSOR_MSGS_INCLUDE)
  message(FATAL_ERROR "ROS1 headers (rosbag/bag.h, sensor_msgs) not found: run scripts/install-deps.sh")
endif()
# rosbag/bag.h includes pluginlib, which Debian installs ament-style in /usr/include/<pkg>/<pkg>.
set(_mmlio_ament_includes "")
foreach(pkg pluginlib class_loader rcutils rcpputils ament_index_cpp)
  if(EXISTS /usr/include/${pkg}/${pkg})
    list(APPEND _mmlio_ament_includes /usr/include/${pkg})
  endif()
endforeach()
find_package(Boost REQUIRED)
add_library(mmlio_ros1 INTERFACE)
target_include_directories(mmlio_ros1 SYSTEM INTERFACE ${MMLIO_ROS_INCLUDE} ${MMLIO_SENSOR_MSGS_INCLUDE} ${_mmlio_ament_includes})
target_link_libraries(mmlio_ros1 INTERFACE ${_mmlio_ros_paths} Boost::boost)
