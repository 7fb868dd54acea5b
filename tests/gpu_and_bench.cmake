find_package(nlohmann_json 3 CONFIG REQUIRED)

# Frame capture + reference glue shared by the GPU tests and the benchmark.
add_library(shadow_test_support STATIC support/frame_capture.cpp)
target_include_directories(shadow_test_support PUBLIC support)
target_link_libraries(shadow_test_support PUBLIC engine_gpu shadows shadow_reference)
engine_target_warnings(shadow_test_support)

# The benchmark: headless, no window-system libraries (it runs on GPU machines without a display).
add_executable(shadow_bench bench/shadow_bench.cpp)
target_link_libraries(shadow_bench PRIVATE shadow_test_support nlohmann_json::nlohmann_json)
engine_target_warnings(shadow_bench)

# GPU tests on lavapipe with the validation layer on.
file(GLOB GPU_TEST_SOURCES CONFIGURE_DEPENDS gpu/*.cpp)
add_executable(gpu_tests ${GPU_TEST_SOURCES})
target_link_libraries(gpu_tests PRIVATE shadow_test_support GTest::gtest_main)
target_compile_definitions(gpu_tests PRIVATE ENGINE_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
engine_target_warnings(gpu_tests)
gtest_discover_tests(gpu_tests DISCOVERY_TIMEOUT 60 PROPERTIES LABELS gpu ENVIRONMENT "ENGINE_VALIDATION=1;ENGINE_DEVICE=lavapipe")

add_subdirectory(window)

# The walkthrough executable itself: headless run, and one-line errors for bad scene files.
add_test(NAME walkthrough_headless_runs
         COMMAND $<TARGET_FILE:walkthrough> --headless --scene contact --size 160x120 --frames 2 --mode hybrid
                 --out ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_test_out)
set_tests_properties(walkthrough_headless_runs PROPERTIES LABELS gpu ENVIRONMENT "ENGINE_DEVICE=lavapipe"
                     PASS_REGULAR_EXPRESSION "wrote .*frame_001.png")
foreach(bad missing_file broken_json index_out_of_range nan_position)
  if(bad STREQUAL missing_file)
    set(file ${PROJECT_SOURCE_DIR}/content/test_gltf/does_not_exist.gltf)
  else()
    set(file ${PROJECT_SOURCE_DIR}/content/test_gltf/${bad}.gltf)
  endif()
  add_test(NAME walkthrough_rejects_${bad}
           COMMAND sh -c "out=$($0 --headless --scene $1 --frames 1 2>&1); rc=$?; echo \"$out\"; \
[ $rc -ne 0 ] && [ $(printf '%s\\n' \"$out\" | wc -l) -eq 1 ] && printf '%s' \"$out\" | grep -q \"$(basename $1)\""
                   $<TARGET_FILE:walkthrough> ${file})
  set_tests_properties(walkthrough_rejects_${bad} PROPERTIES LABELS unit)
endforeach()
add_test(NAME walkthrough_loads_gltf
         COMMAND $<TARGET_FILE:walkthrough> --headless --scene ${PROJECT_SOURCE_DIR}/content/test_gltf/triangle.gltf
                 --size 96x64 --frames 1 --out ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_gltf_out)
set_tests_properties(walkthrough_loads_gltf PROPERTIES LABELS gpu ENVIRONMENT "ENGINE_DEVICE=lavapipe"
                     PASS_REGULAR_EXPRESSION "wrote .*frame_000.png")
set(SPONZA_GLTF ${PROJECT_SOURCE_DIR}/../shared/content/sponza/sponza.gltf)
if(EXISTS ${SPONZA_GLTF})
  add_test(NAME walkthrough_loads_sponza
           COMMAND $<TARGET_FILE:walkthrough> --headless --scene ${SPONZA_GLTF} --size 160x90 --frames 1 --mode izb+csm
                   --out ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_sponza_out)
  set_tests_properties(walkthrough_loads_sponza PROPERTIES LABELS gpu ENVIRONMENT "ENGINE_DEVICE=lavapipe"
                       PASS_REGULAR_EXPRESSION "wrote .*frame_000.png")
endif()

# The minimal integration example renders and writes a non-trivial PNG (png_check fails on a missing,
# tiny or uniform image).
add_executable(png_check tools/png_check.cpp)
target_link_libraries(png_check PRIVATE PkgConfig::STB)
add_test(NAME minimal_example_writes_png
         COMMAND sh -c "rm -f \"$2\" && \"$0\" \"$1\" \"$2\" 2 160x90 && \"$3\" \"$2\" --min-size 160x90 --min-colors 32"
                 $<TARGET_FILE:minimal> contact ${CMAKE_CURRENT_BINARY_DIR}/minimal_example.png $<TARGET_FILE:png_check>)
set_tests_properties(minimal_example_writes_png PROPERTIES LABELS gpu
                     ENVIRONMENT "ENGINE_VALIDATION=1;ENGINE_DEVICE=lavapipe"
                     FAIL_REGULAR_EXPRESSION "\\[vulkan\\]")
add_test(NAME minimal_example_loads_gltf
         COMMAND sh -c "rm -f \"$2\" && \"$0\" \"$1\" \"$2\" 1 96x64 && \"$3\" \"$2\" --min-colors 2 --min-spread 0"
                 $<TARGET_FILE:minimal> ${PROJECT_SOURCE_DIR}/content/test_gltf/triangle.gltf
                 ${CMAKE_CURRENT_BINARY_DIR}/minimal_gltf.png $<TARGET_FILE:png_check>)
set_tests_properties(minimal_example_loads_gltf PROPERTIES LABELS gpu
                     ENVIRONMENT "ENGINE_VALIDATION=1;ENGINE_DEVICE=lavapipe" FAIL_REGULAR_EXPRESSION "\\[vulkan\\]")
