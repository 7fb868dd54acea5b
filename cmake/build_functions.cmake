# Functions shared by the top-level build and a build of modules/shadows on its own.
include_guard(GLOBAL)

# The project's warnings; errors with ENGINE_WARNINGS_AS_ERRORS (the top level) or
# SHADOWS_WARNINGS_AS_ERRORS (modules/shadows on its own).
function(target_strict_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-missing-field-initializers)
  if(ENGINE_WARNINGS_AS_ERRORS OR SHADOWS_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# Position-independent and with hidden symbols when they go into a shared libshadows (whose only
# exported symbols are the shadows:: API).
function(target_packaged_objects target)
  set_target_properties(${target} PROPERTIES CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
  if(SHADOWS_BUILD_SHARED)
    set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  endif()
endfunction()

# Compiles GLSL sources to OUTPUT_DIR/<file name>.spv with glslangValidator (Vulkan 1.3, debug info).
# The depfile it writes makes a change to an included header rebuild the shader. The .spv paths go
# into the variable named by OUT.
#   compile_glsl(OUT var OUTPUT_DIR dir SOURCES a.comp ... INCLUDE_DIRS dir ...)
function(compile_glsl)
  cmake_parse_arguments(ARG "" "OUT;OUTPUT_DIR" "SOURCES;INCLUDE_DIRS" ${ARGN})
  set(includes)
  foreach(dir IN LISTS ARG_INCLUDE_DIRS)
    list(APPEND includes -I${dir})
  endforeach()
  set(outputs)
  foreach(src IN LISTS ARG_SOURCES)
    get_filename_component(name ${src} NAME)
    set(out ${ARG_OUTPUT_DIR}/${name}.spv)
    add_custom_command(
      OUTPUT ${out}
      COMMAND ${CMAKE_COMMAND} -E make_directory ${ARG_OUTPUT_DIR}
      COMMAND ${GLSLANG_VALIDATOR} --quiet -V --target-env vulkan1.3 -g ${includes} --depfile ${out}.d -o ${out} ${src}
      DEPENDS ${src}
      DEPFILE ${out}.d
      COMMENT "glslang ${name}"
      VERBATIM)
    list(APPEND outputs ${out})
  endforeach()
  set(${ARG_OUT} ${outputs} PARENT_SCOPE)
endfunction()
