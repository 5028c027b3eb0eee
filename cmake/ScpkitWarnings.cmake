# Warnings are errors for every scpkit target; sanitizers on request.
add_library(scpkit_warnings INTERFACE)
target_compile_options(scpkit_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
  -Wnon-virtual-dtor -Wold-style-cast -Woverloaded-virtual -Werror)
if(SCPKIT_SANITIZE)
  target_compile_options(scpkit_warnings INTERFACE
    -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  target_link_options(scpkit_warnings INTERFACE -fsanitize=address,undefined)
  # Tests that only measure behaviour over many records skip themselves here (tests/README.md).
  target_compile_definitions(scpkit_warnings INTERFACE SCPKIT_SANITIZED=1)
endif()
