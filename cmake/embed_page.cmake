# Writes a C++ file that holds one page of the CLI (IN, an HTML file) as a raw string, returned by
# penumbra::cli::FUNCTION().
file(READ ${IN} text)
get_filename_component(name ${IN} NAME)
set(body "// Generated from ${name} by cmake/embed_page.cmake. Do not edit.\n#include <string_view>\nnamespace penumbra::cli {\nstd::string_view ${FUNCTION}() {\n  return R\"penumbra_page(${text})penumbra_page\";\n}\n}  // namespace penumbra::cli\n")
file(WRITE ${OUT}.tmp "${body}")
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)
