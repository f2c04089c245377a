# HAPTICD_SANITIZE builds everything (project code and tests) under a sanitizer:
#   ON or address  AddressSanitizer + UndefinedBehaviorSanitizer, any UBSan finding fatal
#   thread         ThreadSanitizer (run on the loop, telemetry and service tests)
# The allocation counter of the tests stands aside under both (they own malloc).
set(HAPTICD_SANITIZE OFF CACHE STRING "OFF, ON/address (ASan+UBSan) or thread (TSan)")
string(TOLOWER "${HAPTICD_SANITIZE}" _hapticd_sanitize)
if(_hapticd_sanitize STREQUAL "on" OR _hapticd_sanitize STREQUAL "address")
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=all
                      -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
  add_compile_definitions(HAPTICD_SANITIZED=1)
elseif(_hapticd_sanitize STREQUAL "thread")
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
  add_compile_definitions(HAPTICD_SANITIZED=1)
elseif(NOT _hapticd_sanitize STREQUAL "off" AND NOT _hapticd_sanitize STREQUAL "")
  message(FATAL_ERROR "HAPTICD_SANITIZE must be OFF, ON, address or thread, got '${HAPTICD_SANITIZE}'")
endif()
