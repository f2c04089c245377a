# HAPTICD_SANITIZE=ON builds everything (project code and tests) with ASan and UBSan, and
# makes any UBSan finding fatal so the test suite fails on it.
if(HAPTICD_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=all
                      -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
  add_compile_definitions(HAPTICD_SANITIZED=1)
endif()
