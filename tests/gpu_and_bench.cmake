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
