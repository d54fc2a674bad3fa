# kodawari_embed_shaders(TARGET <target> SOURCES <file.comp|.vert|.frag>... INCLUDE_DIRS <dir>...)
#
# Compiles each shader (glslang infers the stage from the extension) to SPIR-V at build time with glslangValidator (its
# --depfile tracks the #included files, so editing shaders/shared/*.h or the GLSL library
# shaders/lib/*.glsl rebuilds what uses it; both are reached as "shared/..." and "lib/..."
# from the shader directory in INCLUDE_DIRS) and embeds the words in a C++ source added to <target>:
# kodawari::gpu::embedded_shader("<name>") returns them. A compute kernel's name is its
# file name without .comp ("rods_step"); a graphics stage keeps its extension
# ("render.vert"), since a vertex and a fragment shader usually share a base name.
# A source given as <file.comp>@<name>@<MACRO> is that file compiled once more with MACRO
# defined, as kernel <name>: a variant that differs in what a specialization constant
# cannot change (rods_step.comp@rods_step_shared@KW_RODS_SHARED_CONSTANTS).
function(kodawari_embed_shaders)
  cmake_parse_arguments(ARG "" "TARGET" "SOURCES;INCLUDE_DIRS" ${ARGN})
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/spirv)
  file(MAKE_DIRECTORY ${out_dir})
  set(include_flags)
  foreach(dir IN LISTS ARG_INCLUDE_DIRS)
    list(APPEND include_flags -I${dir})
  endforeach()
  set(headers)
  set(includes "")
  set(entries "")
  foreach(entry IN LISTS ARG_SOURCES)
    set(defines)
    if(entry MATCHES "^(.+)@(.+)@(.+)$")
      set(src ${CMAKE_MATCH_1})
      set(variant_key ${CMAKE_MATCH_2})
      set(defines -D${CMAKE_MATCH_3})
    else()
      set(src ${entry})
      set(variant_key)
    endif()
    get_filename_component(file_name ${src} NAME)
    get_filename_component(ext ${src} LAST_EXT)
    if(variant_key)
      set(key ${variant_key})
    elseif(ext STREQUAL ".comp")
      get_filename_component(key ${src} NAME_WE)
    else()
      set(key ${file_name})
    endif()
    string(MAKE_C_IDENTIFIER ${key} name)
    get_filename_component(abs ${src} ABSOLUTE)
    set(header ${out_dir}/${name}.spv.h)
    add_custom_command(
      OUTPUT ${header}
      COMMAND Vulkan::glslangValidator --quiet --target-env vulkan1.1 -V ${include_flags} ${defines}
              --vn kodawari_spirv_${name} --depfile ${header}.d -o ${header} ${abs}
      DEPENDS ${abs}
      DEPFILE ${header}.d
      COMMENT "glslang ${file_name}"
      VERBATIM)
    list(APPEND headers ${header})
    string(APPEND includes "#include \"${name}.spv.h\"\n")
    string(APPEND entries "    {\"${key}\", std::span<const std::uint32_t>(kodawari_spirv_${name})},\n")
  endforeach()
  set(KODAWARI_SHADER_INCLUDES "${includes}")
  set(KODAWARI_SHADER_ENTRIES "${entries}")
  configure_file(${PROJECT_SOURCE_DIR}/cmake/embedded_shaders.cpp.in ${out_dir}/embedded_shaders.cpp @ONLY)
  target_sources(${ARG_TARGET} PRIVATE ${headers} ${out_dir}/embedded_shaders.cpp)
  target_include_directories(${ARG_TARGET} PRIVATE ${out_dir})
endfunction()
