# kodawari_embed_file(TARGET <target> SOURCE <file> NAME <identifier>)
#
# Embeds the bytes of <file> (docs/scene.schema.json for `kodawari schema`) in a C++ source
# added to <target>: kodawari::embedded::<identifier>() returns them as a std::string_view.
# As for the shaders (KodawariShaders.cmake), the source is generated at build time by a
# custom command that depends on <file>, so editing the file rebuilds the binary and the
# binary never serves a stale copy; configure time would only see the file once.
set(KODAWARI_EMBED_SCRIPT ${CMAKE_CURRENT_LIST_DIR}/embed_file.cmake)
function(kodawari_embed_file)
  cmake_parse_arguments(ARG "" "TARGET;SOURCE;NAME" "" ${ARGN})
  get_filename_component(abs ${ARG_SOURCE} ABSOLUTE)
  get_filename_component(file_name ${ARG_SOURCE} NAME)
  set(out ${CMAKE_CURRENT_BINARY_DIR}/embedded/${ARG_NAME}.cpp)
  add_custom_command(
    OUTPUT ${out}
    COMMAND ${CMAKE_COMMAND} -DINPUT=${abs} -DOUTPUT=${out} -DNAME=${ARG_NAME} -P ${KODAWARI_EMBED_SCRIPT}
    DEPENDS ${abs} ${KODAWARI_EMBED_SCRIPT}
    COMMENT "embed ${file_name}"
    VERBATIM)
  target_sources(${ARG_TARGET} PRIVATE ${out})
endfunction()
