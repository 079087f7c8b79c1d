# cmake -P script: writes OUT, a C++ file defining one `const char*` per shader file.
# Arguments: -DOUT=file.cpp -DINPUTS=a.vert,b.frag
file(WRITE "${OUT}.tmp" "// Generated from preview/shaders by EmbedShaders.cmake. Do not edit.\nnamespace meso::shaders {\n")
string(REPLACE "," ";" INPUTS "${INPUTS}")
foreach(in IN LISTS INPUTS)
  get_filename_component(name "${in}" NAME)
  string(MAKE_C_IDENTIFIER "${name}" id)
  file(READ "${in}" text)
  file(APPEND "${OUT}.tmp" "extern const char* const ${id};\nconst char* const ${id} = R\"meso_glsl(${text})meso_glsl\";\n")
endforeach()
file(APPEND "${OUT}.tmp" "}  // namespace meso::shaders\n")
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
