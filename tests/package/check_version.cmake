# Which requested versions the installed kodawariConfigVersion.cmake accepts, as
# find_package(kodawari <request>) asks it:
#   cmake -DVERSION_FILE=<prefix>/lib/cmake/kodawari/kodawariConfigVersion.cmake -P check_version.cmake
# While Kodawari is 0.x a minor release may break the API: 0.3 accepts 0.3 and 0.3.x
# requests only.
cmake_minimum_required(VERSION 3.25)
# 0.3.99 is newer than this 0.3.0; `0` reads as 0.0 (find_package gives a missing minor as 0).
# 0.2 is refused: 0.3 changed the C ABI (kodawari_backend_options grew).
set(accepted 0.3 0.3.0)
set(refused 0 0.1 0.2 0.2.0 0.4 1.0 0.3.99)
foreach(request IN LISTS accepted refused)
  unset(PACKAGE_VERSION_COMPATIBLE)
  unset(PACKAGE_VERSION_EXACT)
  set(PACKAGE_FIND_VERSION ${request})
  string(REPLACE "." ";" parts "${request}.0.0.0")
  list(GET parts 0 PACKAGE_FIND_VERSION_MAJOR)
  list(GET parts 1 PACKAGE_FIND_VERSION_MINOR)
  list(GET parts 2 PACKAGE_FIND_VERSION_PATCH)
  string(REPLACE "." ";" count "${request}")
  list(LENGTH count PACKAGE_FIND_VERSION_COUNT)
  include(${VERSION_FILE})
  if(request IN_LIST accepted AND NOT PACKAGE_VERSION_COMPATIBLE)
    message(FATAL_ERROR "kodawari ${PACKAGE_VERSION} refuses a request for ${request}")
  elseif(request IN_LIST refused AND PACKAGE_VERSION_COMPATIBLE)
    message(FATAL_ERROR "kodawari ${PACKAGE_VERSION} accepts a request for ${request}")
  endif()
endforeach()
list(JOIN accepted ", " accepted)
list(JOIN refused ", " refused)
message(STATUS "kodawari ${PACKAGE_VERSION}: accepts requests for ${accepted}; refuses ${refused}")
