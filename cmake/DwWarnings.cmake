# dw_warnings(target): the house warning set for our own code (not generated code).
function(dw_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast)
endfunction()
