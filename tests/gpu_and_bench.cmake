find_package(nlohmann_json 3 CONFIG REQUIRED)

# Frame capture + reference glue shared by the GPU tests and the benchmark.
add_library(shadow_test_support STATIC support/frame_capture.cpp support/penumbra_mask.cpp)
target_include_directories(shadow_test_support PUBLIC support)
target_link_libraries(shadow_test_support PUBLIC engine_gpu shadows_engine shadow_reference)
target_strict_warnings(shadow_test_support)

# The benchmark: headless, no window-system libraries (it runs on GPU machines without a display).
add_executable(shadow_bench bench/shadow_bench.cpp)
target_link_libraries(shadow_bench PRIVATE shadow_test_support nlohmann_json::nlohmann_json)
target_strict_warnings(shadow_bench)

# GPU tests on lavapipe with the validation layer on.
file(GLOB GPU_TEST_SOURCES CONFIGURE_DEPENDS gpu/*.cpp)
add_executable(gpu_tests ${GPU_TEST_SOURCES})
target_link_libraries(gpu_tests PRIVATE shadow_test_support GTest::gtest_main)
# The backend probe is tested directly (modules/shadows/src/backend_probe.hpp, the module's own header).
target_include_directories(gpu_tests PRIVATE ${PROJECT_SOURCE_DIR}/modules/shadows/src)
target_compile_definitions(gpu_tests PRIVATE ENGINE_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
target_strict_warnings(gpu_tests)
# Discovered tests take a flat PROPERTIES list: one label and one ENVIRONMENT entry each (a CMake list
# there would be split into keys and values). The layer is on either way: the GPU fixture forces it.
#
# The GPU smoke set (label gpu_smoke, in the plain run like the rest of label gpu): what the sanitizer
# run (.ci/sanitize) protects beyond the unit and reference tests, the module's and engine's CPU code on
# every path: context and device adoption, every refusal, pool growth and overflow, resize, each
# technique and light type once, moving casters, skinned casters, overlays, alpha-tested materials.
set(GPU_SMOKE_FILTER "GpuTest.*:AdoptedDeviceTest.*:RobustnessTest.*InOneLine:RobustnessTest.LiveAllocation*:\
IzbTest.TinyNodePool*:IzbTest.NodePoolGrows*:IzbTest.Resize*:IzbTest.HybridNearPoints*:\
CascadesTest.DebugOverlaysAndCullingChoice:RayTracedTest.DeviceWithoutRayTracing*:RayTracedTest.EveryLightOfAFrame*:\
Levels/DynamicSceneTest.*/wall:Lights/LocalLightTest.ShadowMapsOfTheLight/*:Scenes/IzbSceneTest.OneSample*/contact_view0:\
MaterialsTest.GbufferAlphaTests*:Features/MaskedFeatureTest.PathsThatNeedTheFeatureRefuseInOneLine/*:\
Clips/AnimatedCastersTest.*/skinned_cylinder")
# The rest of the per-scene sweeps of the equivalence tests (an optimisation changes no verdict: lit
# culling, anchored nodes, compute against raster; every shape of the IZB's first step) and the 512²
# lamps run under `long`; the plain run keeps one scene of each sweep and the 256² lamps.
set(GPU_LONG_FILTER "Scenes/IzbSceneTest.LitCullingIsExact/atrium*:Scenes/IzbSceneTest.LitCullingIsExact/canopy*:\
Scenes/IzbSceneTest.LitCullingIsExact/contact_view1:Scenes/IzbSceneTest.LitCullingIsExact/foliage*:\
Scenes/IzbSceneTest.AnchoredNodes*/atrium*:Scenes/IzbSceneTest.AnchoredNodes*/foliage*:\
Scenes/IzbSceneTest.AnchoredNodes*/contact_view1:Scenes/IzbSceneTest.AnchoredNodes*/canopy*:\
Scenes/IzbSceneTest.ComputeAndRaster*/atrium*:Scenes/IzbSceneTest.ComputeAndRaster*/canopy*:\
Scenes/IzbSceneTest.ComputeAndRaster*/contact_view0:Scenes/IzbSceneTest.ComputeAndRaster*/foliage*:\
IzbTest.EveryStepOneShapeGivesTheSameAnswer:Lamps/LampsTest.*_512")
gtest_discover_tests(gpu_tests DISCOVERY_TIMEOUT 60 TEST_FILTER "${GPU_SMOKE_FILTER}"
                     PROPERTIES LABELS gpu_smoke TIMEOUT 900 ENVIRONMENT ENGINE_VALIDATION=1)
gtest_discover_tests(gpu_tests DISCOVERY_TIMEOUT 60 TEST_FILTER "${GPU_LONG_FILTER}"
                     PROPERTIES LABELS long TIMEOUT 900 ENVIRONMENT ENGINE_VALIDATION=1)
gtest_discover_tests(gpu_tests DISCOVERY_TIMEOUT 60 TEST_FILTER "*-${GPU_SMOKE_FILTER}:${GPU_LONG_FILTER}"
                     PROPERTIES LABELS gpu TIMEOUT 900 ENVIRONMENT ENGINE_VALIDATION=1)
# A third of the GPU suite (every third test in gtest's order, the `long` ones left out) through the
# host path: ENGINE_HOST_INPUTS=1 hands every module the engine's G-buffer as any other engine would,
# so the input pass rebuilds the shading points the tests then check (HostInputsTest compares the two
# paths bit for bit). Two entries of gtest's shards 0 and 3 of 6, which are the tests of shard 0 of 3.
foreach(shard 0 3)
  add_test(NAME host_inputs_suite_${shard} COMMAND gpu_tests "--gtest_filter=-${GPU_LONG_FILTER}")
  set_tests_properties(host_inputs_suite_${shard} PROPERTIES LABELS gpu TIMEOUT 1800
    ENVIRONMENT "ENGINE_HOST_INPUTS=1;ENGINE_VALIDATION=1;GTEST_TOTAL_SHARDS=6;GTEST_SHARD_INDEX=${shard}")
endforeach()
add_test(NAME host_inputs_switch COMMAND gpu_tests "--gtest_filter=GpuTest.HostInputsEnvironmentPicksThePath")
set_tests_properties(host_inputs_switch PROPERTIES LABELS gpu TIMEOUT 300 ENVIRONMENT "ENGINE_HOST_INPUTS=1;ENGINE_VALIDATION=1")
# The same tests with the validation layer's synchronization checks on: a hazard between commands (a
# missing or too narrow barrier) is a validation message, so a failure. Label syncval runs a
# representative set: every technique and light type, both trace and CSM backends, several lights in
# one record, moving casters over many frames, resize, pool growth, overlays, 32 spp. The whole suite
# under synchronization validation is one entry under `long` (syncval_gpu_suite).
set(SYNCVAL_FILTER "RobustnessTest.SyncValidationReportsAMissingBarrier:IzbTest.Resize*:IzbTest.NodePoolGrows*:\
IzbTest.TimedCsmTimesBothAndKeepsOne:IzbTest.AutomaticBackendsKeepTheFasterMeasuredPass:IzbTest.HybridNearPoints*:\
IzbTest.DebugOverlays*:CascadesTest.MaskingMatchesUnmaskedAndSavesWork:CascadesTest.DebugOverlaysAndCullingChoice:\
Levels/DynamicSceneTest.*:RayTracedTest.EveryLightOfAFrame*:RayTracedTest.IzbSpotLightTraces*:\
Lights/LocalLightTest.ShadowMapsOfTheLight/*:MaterialsTest.SmoothTerminator*:GpuTest.HeadlessImageShowsLitGeometry:\
Scenes/IzbSceneTest.ComputeAndRasterPassesAgreeBitForBit/contact_view0:Scenes/IzbSceneTest.ThirtyTwoSamples*/contact_view0:\
Views/CanopyTest.*/view0_256:Clips/AnimatedCastersTest.*:AdoptedDeviceTest.RunsOnTheHostDeviceAndLeavesItAlive:Scenes/HostInputsTest.*/contact_view0")
gtest_discover_tests(gpu_tests DISCOVERY_TIMEOUT 60 TEST_PREFIX syncval. TEST_FILTER "${SYNCVAL_FILTER}"
                     PROPERTIES LABELS syncval TIMEOUT 900 ENVIRONMENT ENGINE_SYNC_VALIDATION=1)
add_test(NAME syncval_gpu_suite COMMAND gpu_tests)
set_tests_properties(syncval_gpu_suite PROPERTIES LABELS long TIMEOUT 14400 ENVIRONMENT ENGINE_SYNC_VALIDATION=1)

# Exact anywhere: the scale and offset matrix against Embree (tests/scale), one CTest entry per scene,
# validation on; outside gpu_tests so the synchronization-validation pass does not run it twice. The
# plain run (label scale) takes every placement of every scene and the room-scale hall (about 290 s on
# two cores, the entries two at a time).
add_executable(world_scale_tests scale/world_scale_test.cpp)
target_link_libraries(world_scale_tests PRIVATE shadow_test_support GTest::gtest_main)
target_compile_definitions(world_scale_tests PRIVATE ENGINE_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
target_strict_warnings(world_scale_tests)
gtest_discover_tests(world_scale_tests DISCOVERY_TIMEOUT 60
                     PROPERTIES LABELS scale TIMEOUT 1800 ENVIRONMENT ENGINE_VALIDATION=1)

add_subdirectory(window)

# The walkthrough executable itself: headless run, and one-line errors for bad scene files.
# The walkthrough and example runs go through check_run.sh: exit code, validation messages, and the
# frames they write (non-trivial; in shadow modes, pixels darker than the same frame with `--mode off`:
# each --min-darker is about half the share seen on lavapipe; Sponza's overview from above shows little
# shadow, 0.19 %).
set(CHECK_RUN ${PROJECT_SOURCE_DIR}/tests/check_run.sh)
set(CHECK_RUN_ENV "PNG_CHECK=$<TARGET_FILE:png_check>;ENGINE_DEVICE=lavapipe")
set(out ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_test_out)
set(args --headless --scene contact --size 160x120 --frames 2)
add_test(NAME walkthrough_headless_runs
         COMMAND ${CHECK_RUN} --fresh ${out} --fresh ${out}_off
                 --png "${out}/frame_000.png --min-size 160x120"
                 --png "${out}/frame_001.png --min-size 160x120 --darker-than ${out}_off/frame_001.png --min-darker 0.004"
                 -- $<TARGET_FILE:walkthrough> ${args} --mode hybrid --out ${out}
                 --then $<TARGET_FILE:walkthrough> ${args} --mode off --out ${out}_off)
set_tests_properties(walkthrough_headless_runs PROPERTIES LABELS gpu ENVIRONMENT "${CHECK_RUN_ENV}")
# The courtyard at night: the moon and the three lamps, each with its own shadow term from one record.
set(out ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_night_out)
set(args --headless --size 240x136 --frames 1 --time-of-day 22)
add_test(NAME walkthrough_night_lamps
         COMMAND ${CHECK_RUN} --fresh ${out} --fresh ${out}_off
                 --png "${out}/frame_000.png --min-size 240x136 --darker-than ${out}_off/frame_000.png --min-darker 0.01"
                 -- $<TARGET_FILE:walkthrough> ${args} --mode hybrid --out ${out}
                 --then $<TARGET_FILE:walkthrough> ${args} --mode off --out ${out}_off)
set_tests_properties(walkthrough_night_lamps PROPERTIES LABELS gpu ENVIRONMENT "${CHECK_RUN_ENV}")
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
  set_tests_properties(walkthrough_rejects_${bad} PROPERTIES LABELS unit ENVIRONMENT ENGINE_VALIDATION=1)
endforeach()
set(out ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_gltf_out)
add_test(NAME walkthrough_loads_gltf
         COMMAND ${CHECK_RUN} --fresh ${out} --png "${out}/frame_000.png --min-colors 2 --min-spread 0"
                 -- $<TARGET_FILE:walkthrough> --headless --scene ${PROJECT_SOURCE_DIR}/content/test_gltf/triangle.gltf
                 --size 96x64 --frames 1 --out ${out})
set_tests_properties(walkthrough_loads_gltf PROPERTIES LABELS gpu ENVIRONMENT "${CHECK_RUN_ENV}")
set(SPONZA_GLTF ${PROJECT_SOURCE_DIR}/../shared/content/sponza/sponza.gltf)
if(EXISTS ${SPONZA_GLTF})
  set(out ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_sponza_out)
  set(args --headless --scene ${SPONZA_GLTF} --size 160x90 --frames 1)
  add_test(NAME walkthrough_loads_sponza
           COMMAND ${CHECK_RUN} --fresh ${out} --fresh ${out}_off
                   --png "${out}/frame_000.png --min-size 160x90 --darker-than ${out}_off/frame_000.png --min-darker 0.001"
                   -- $<TARGET_FILE:walkthrough> ${args} --mode izb+csm --out ${out}
                   --then $<TARGET_FILE:walkthrough> ${args} --mode off --out ${out}_off)
  set_tests_properties(walkthrough_loads_sponza PROPERTIES LABELS gpu ENVIRONMENT "${CHECK_RUN_ENV}")
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

# The walkthrough game: replayed input, recording, scene files, tours.
set(TEST_LEVELS ${PROJECT_SOURCE_DIR}/content/test_levels)
add_test(NAME walkthrough_replay_walks_into_wall
         COMMAND ${PROJECT_SOURCE_DIR}/tests/check_player.sh 3.9 4.1 -0.05 0.05 -4.75 -4.6
                 $<TARGET_FILE:walkthrough> --headless --scene ${TEST_LEVELS}/wall.json
                 --input ${TEST_LEVELS}/walk_into_wall.input --size 96x64 --mode sm
                 --out ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_replay_out)
set_tests_properties(walkthrough_replay_walks_into_wall PROPERTIES LABELS gpu
                     ENVIRONMENT "ENGINE_VALIDATION=1;ENGINE_DEVICE=lavapipe" FAIL_REGULAR_EXPRESSION "\\[vulkan\\]")
# Recording while replaying writes a script that replays to the same place. (Each run's output is kept
# before grep reads it: in a pipeline the walkthrough's exit code would be lost.)
add_test(NAME walkthrough_record_replays_identically
         COMMAND sh -c "set -e; rec=$2/recorded.input; rm -f $rec; \
a=$($0 --headless --scene $1/wall.json --input $1/walk_into_wall.input --size 64x48 --mode off --out $2 --record $rec); \
b=$($0 --headless --scene $1/wall.json --input $rec --size 64x48 --mode off --out $2); \
a=$(printf '%s\\n' \"$a\" | grep '^player:'); b=$(printf '%s\\n' \"$b\" | grep '^player:'); \
echo \"$a\"; echo \"$b\"; [ -n \"$a\" ] && [ \"$a\" = \"$b\" ]"
                 $<TARGET_FILE:walkthrough> ${TEST_LEVELS} ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_record_out)
set_tests_properties(walkthrough_record_replays_identically PROPERTIES LABELS gpu ENVIRONMENT "ENGINE_VALIDATION=1;ENGINE_DEVICE=lavapipe"
                     FAIL_REGULAR_EXPRESSION "\\[vulkan\\]")
# Bad scene files and input scripts: one line naming the file (and the field or line), exit code 1.
foreach(bad bad_json bad_field bad_shape bad_shadow_flag bad_animation bad_script)
  if(bad STREQUAL bad_script)
    set(args --scene ${TEST_LEVELS}/wall.json --input ${TEST_LEVELS}/bad_script.input)
    set(expect "bad_script.input:3: unknown key 'Jump'")
  else()
    set(args --scene ${TEST_LEVELS}/${bad}.json)
  endif()
  if(bad STREQUAL bad_json)
    set(expect "bad_json.json: not valid JSON")
  elseif(bad STREQUAL bad_field)
    set(expect "bad_field.json: objects.1..shape.box.max: expected an array of 3 numbers")
  elseif(bad STREQUAL bad_shape)
    set(expect "bad_shape.json: objects.0..shape.pyramid: unknown shape")
  elseif(bad STREQUAL bad_shadow_flag)
    set(expect "bad_shadow_flag.json: objects.1..shadow.csm: 'sometimes' is not one of on, off, auto")
  elseif(bad STREQUAL bad_animation)
    set(expect "bad_animation.json: objects.1..animate.walk.path: expected at least 2 points")
  endif()
  add_test(NAME walkthrough_rejects_${bad}
           COMMAND sh -c "out=$(\"$@\" --headless --frames 1 2>&1); rc=$?; echo \"$out\"; \
[ $rc -eq 1 ] && [ $(printf '%s\\n' \"$out\" | wc -l) -eq 1 ] && printf '%s' \"$out\" | grep -q \"$0\""
                   "${expect}" $<TARGET_FILE:walkthrough> ${args})
  set_tests_properties(walkthrough_rejects_${bad} PROPERTIES LABELS unit ENVIRONMENT ENGINE_VALIDATION=1)
endforeach()
# shadow_bench --scale/--offset: a scene float cannot hold is refused in one line naming the option.
set(bench_bad_scale_0 "--scale 0" "--scale must be positive")
set(bench_bad_scale_nan "--scale nan" "--scale 'nan': expected a finite number")
set(bench_bad_scale_huge "--scale 1e30" "--scale/--offset scale 1e+30")
set(bench_bad_offset_inf "--offset inf,0,0" "--offset 'inf': expected a finite number")
set(bench_bad_offset_far "--offset 1e8,0,0" "out of float's reach")
set(bench_bad_offset_two "--offset 1,2" "--offset '1,2': expected X,Y,Z")
foreach(bad scale_0 scale_nan scale_huge offset_inf offset_far offset_two)
  list(GET bench_bad_${bad} 0 option)
  list(GET bench_bad_${bad} 1 expect)
  separate_arguments(option)
  add_test(NAME shadow_bench_refuses_${bad}
           COMMAND sh -c "out=$(\"$@\" 2>&1); rc=$?; echo \"$out\"; \
[ $rc -ne 0 ] && [ $(printf '%s\\n' \"$out\" | wc -l) -eq 1 ] && printf '%s' \"$out\" | grep -qF -- \"$0\""
                   "${expect}" $<TARGET_FILE:shadow_bench> --scene contact --size 32x32 --frames 1 --warmup 0 ${option})
  set_tests_properties(shadow_bench_refuses_${bad} PROPERTIES LABELS unit ENVIRONMENT ENGINE_DEVICE=lavapipe)
endforeach()
# A headless tour of every shipped level at a small size, with moving casters and a moving sun.
file(GLOB SHIPPED_LEVELS CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/content/levels/*.json)
foreach(level ${SHIPPED_LEVELS})
  get_filename_component(level_name ${level} NAME_WE)
  set(out ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_tour_${level_name})
  set(args --headless --tour --animate-sun --scene ${level} --size 128x72 --frames 3)
  set(pngs)
  foreach(f 000 001 002)
    list(APPEND pngs --png "${out}/frame_${f}.png --min-size 128x72 --darker-than ${out}_off/frame_${f}.png --min-darker 0.03")
  endforeach()
  add_test(NAME walkthrough_tour_${level_name}
           COMMAND ${CHECK_RUN} --fresh ${out} --fresh ${out}_off ${pngs}
                   -- $<TARGET_FILE:walkthrough> ${args} --out ${out}
                   --then $<TARGET_FILE:walkthrough> ${args} --mode off --out ${out}_off)
  set_tests_properties(walkthrough_tour_${level_name} PROPERTIES LABELS gpu ENVIRONMENT "${CHECK_RUN_ENV}")
endforeach()
# Settings files: loaded, saved, and loaded back; a bad one is rejected in one line.
add_test(NAME walkthrough_settings_round_trip
         COMMAND sh -c "set -e; rm -f $2; o=$($0 --headless --scene $1/wall.json --settings $1/settings.json --save-settings $2 \
--size 64x48 --frames 1 --out $3); printf '%s' \"$o\" | grep -q 'mode sm,'; \
o=$($0 --headless --scene $1/wall.json --settings $2 --size 64x48 --frames 1 --out $3); printf '%s' \"$o\" | grep 'mode sm,'; \
grep -q '\"time_of_day\": 9.5' $2"
                 $<TARGET_FILE:walkthrough> ${TEST_LEVELS} ${CMAKE_CURRENT_BINARY_DIR}/saved_settings.json
                 ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_settings_out)
set_tests_properties(walkthrough_settings_round_trip PROPERTIES LABELS gpu ENVIRONMENT "ENGINE_VALIDATION=1;ENGINE_DEVICE=lavapipe"
                     FAIL_REGULAR_EXPRESSION "\\[vulkan\\]")
add_test(NAME walkthrough_rejects_bad_settings
         COMMAND sh -c "out=$(\"$0\" \"$@\" 2>&1); rc=$?; echo \"$out\"; [ $rc -eq 1 ] && [ $(printf '%s\\n' \"$out\" | wc -l) -eq 1 ] \
&& printf '%s' \"$out\" | grep -q 'bad_settings.json: samples_per_pixel: must be 1 or 32'"
                 $<TARGET_FILE:walkthrough> --headless --scene ${TEST_LEVELS}/wall.json --settings ${TEST_LEVELS}/bad_settings.json
                 --size 64x48 --frames 1 --out ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_settings_out)
set_tests_properties(walkthrough_rejects_bad_settings PROPERTIES LABELS gpu ENVIRONMENT "ENGINE_VALIDATION=1;ENGINE_DEVICE=lavapipe"
                     FAIL_REGULAR_EXPRESSION "\\[vulkan\\]")
if(EXISTS ${SPONZA_GLTF})
  set(out ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_tour_sponza)
  set(args --headless --tour --scene ${PROJECT_SOURCE_DIR}/content/sponza/sponza.json --size 96x54 --frames 2)
  add_test(NAME walkthrough_tour_sponza
           COMMAND ${CHECK_RUN} --fresh ${out} --fresh ${out}_off
                   --png "${out}/frame_000.png --min-size 96x54 --darker-than ${out}_off/frame_000.png --min-darker 0.1"
                   --png "${out}/frame_001.png --min-size 96x54 --darker-than ${out}_off/frame_001.png --min-darker 0.1"
                   -- $<TARGET_FILE:walkthrough> ${args} --mode sm --out ${out}
                   --then $<TARGET_FILE:walkthrough> ${args} --mode off --out ${out}_off)
  set_tests_properties(walkthrough_tour_sponza PROPERTIES LABELS gpu ENVIRONMENT "${CHECK_RUN_ENV}")
endif()

# The ray-traced technique on a device without ray tracing (lavapipe): the benchmark and the
# walkthrough refuse `--mode rt` with one line naming the missing extension.
set(ONE_LINE_ERROR_NAMING_EXTENSION
    "out=$(\"$@\" 2>&1); rc=$?; echo \"$out\"; [ $rc -ne 0 ] && [ $(printf '%s\\n' \"$out\" | wc -l) -eq 1 ] && printf '%s' \"$out\" | grep -q 'lacks VK_KHR_'")
add_test(NAME shadow_bench_rt_without_ray_tracing_one_line
         COMMAND sh -c "${ONE_LINE_ERROR_NAMING_EXTENSION}" sh $<TARGET_FILE:shadow_bench> --mode rt --size 64x64 --frames 1)
add_test(NAME walkthrough_rt_without_ray_tracing_one_line
         COMMAND sh -c "${ONE_LINE_ERROR_NAMING_EXTENSION}" sh $<TARGET_FILE:walkthrough> --headless --scene contact
                 --size 64x64 --frames 1 --mode rt --out ${CMAKE_CURRENT_BINARY_DIR}/walkthrough_rt_out)
set_tests_properties(shadow_bench_rt_without_ray_tracing_one_line walkthrough_rt_without_ray_tracing_one_line
                     PROPERTIES LABELS gpu ENVIRONMENT "ENGINE_VALIDATION=1;ENGINE_DEVICE=lavapipe"
                     FAIL_REGULAR_EXPRESSION "\\[vulkan\\]")

# The benchmark's bounds make a run a check: on contact the one-tap shadow map is over a mismatch bound
# of 0.02 % (exit code 2, the mode and the figure named), the IZB within it at 1 spp and, at 32 spp,
# within the coverage bound too.
add_test(NAME shadow_bench_reference_bounds
         COMMAND sh -c "set -x; b=\"$0 --scene contact --view 0 --size 128x128 --izb 256 --frames 1 --warmup 0 --reference\"; \
$b --mode izb --max-mismatch 0.0002 && $b --mode izb --spp 32 --max-mismatch 0.0002 --max-coverage-mae 0.001 || exit 1; \
err=$($b --mode sm --max-mismatch 0.0002 2>&1 >/dev/null); rc=$?; echo \"$err\"; \
[ $rc -eq 2 ] && printf '%s' \"$err\" | grep -q 'sm (contact view 0, 1 spp): mismatch rate .* over --max-mismatch'"
                 $<TARGET_FILE:shadow_bench>)
set_tests_properties(shadow_bench_reference_bounds PROPERTIES LABELS gpu
                     ENVIRONMENT "ENGINE_VALIDATION=1;ENGINE_DEVICE=lavapipe" FAIL_REGULAR_EXPRESSION "\\[vulkan\\]")

# A spot light handed over with set_light (--light spot) in a world 1e5 units out through Scene::origin
# (--large-world): the adapter rebases its scene-space position like the rest, and the IZB matches Embree.
add_test(NAME shadow_bench_large_world_spot
         COMMAND $<TARGET_FILE:shadow_bench> --scene lamps --light spot --large-world --offset 100000,0,100000
                 --size 128x128 --izb 256 --mode izb --reference --frames 1 --warmup 0 --max-mismatch 0.0002)
set_tests_properties(shadow_bench_large_world_spot PROPERTIES LABELS gpu TIMEOUT 300
                     ENVIRONMENT "ENGINE_VALIDATION=1;ENGINE_DEVICE=lavapipe" FAIL_REGULAR_EXPRESSION "\\[vulkan\\]")

# The paper suite at small sizes: every technique on every view of two scenes, both tables written;
# every run but those lavapipe cannot make (rt, the hardware coverage tests) must have run.
add_test(NAME shadow_bench_suite_paper_quick
         COMMAND sh -c "rm -rf \"$1\" && \"$0\" --suite paper --quick --scene contact,atrium --views 1 --frames 2 --warmup 0 --out \"$1\" \
&& grep -q 'Table 2 layout: 320x180' \"$1/suite.md\" && grep -q 'Table 3 layout' \"$1/suite.md\" \
&& grep -q '\"mode\": \"rt\"' \"$1/suite.json\" && ! grep -q '\"validation_messages\": [1-9]' \"$1/suite.json\" \
&& python3 -c \"import json, sys; bad = [r['mode'] + ' ' + r.get('csm_test', '') for r in json.load(open(sys.argv[1])) \
if r['status'] != 'ran' and r['mode'] != 'rt' and r.get('csm_test') not in ('bary-hw', 'inner-hw')]; \
sys.exit('unavailable on this device: ' + ', '.join(bad) if bad else 0)\" \"$1/suite.json\""
                 $<TARGET_FILE:shadow_bench> ${CMAKE_CURRENT_BINARY_DIR}/suite_quick)
set_tests_properties(shadow_bench_suite_paper_quick PROPERTIES LABELS gpu
                     ENVIRONMENT "ENGINE_VALIDATION=1;ENGINE_DEVICE=lavapipe" FAIL_REGULAR_EXPRESSION "\\[vulkan\\]")

# Scale on lavapipe: Sponza x16 (over a million triangles) with every technique at a small size; each
# must run without validation messages (buffers are sized from the demand, or refused with the figures).
if(EXISTS ${SPONZA_GLTF})
  add_test(NAME shadow_bench_million_triangles
           COMMAND sh -c "\"$0\" --scene \"$1\" --view 1 --instances 16 --size 160x90 --izb 256 \
--mode sm,cascades,izb,izb+csm,hybrid+csm --trace compute --csm-backend compute --frames 1 --warmup 0 --json \"$2\" \
&& python3 -c \"import json, sys; runs = json.load(open(sys.argv[1])); \
sys.exit(0 if len(runs) == 5 and all(r['status'] == 'ran' and r['triangles'] >= 1000000 and r['validation_messages'] == 0 \
and r['memory_total_bytes'] > 0 for r in runs) else 'a technique did not run at scale')\" \"$2\""
                   $<TARGET_FILE:shadow_bench> ${SPONZA_GLTF} ${CMAKE_CURRENT_BINARY_DIR}/million_triangles.json)
  set_tests_properties(shadow_bench_million_triangles PROPERTIES LABELS long TIMEOUT 600
                       ENVIRONMENT "ENGINE_VALIDATION=1;ENGINE_DEVICE=lavapipe" FAIL_REGULAR_EXPRESSION "\\[vulkan\\]")
endif()

# Soak: 10,000 frames cycling every mode with moving sun and casters; resident memory and live
# allocations must stay flat after warm-up. Long: under the `long` label, which .ci/run leaves out.
add_executable(shadow_soak soak/soak.cpp)
target_link_libraries(shadow_soak PRIVATE engine_gpu shadows_engine)
target_strict_warnings(shadow_soak)
add_test(NAME soak_contact_10000_frames COMMAND $<TARGET_FILE:shadow_soak> --frames 10000 --size 64x48)
set_tests_properties(soak_contact_10000_frames PROPERTIES LABELS "long;soak" TIMEOUT 14400
                     ENVIRONMENT "ENGINE_DEVICE=lavapipe")

# The raw-Vulkan host (sample_game/vulkan_host): its PNG (flat-shaded: few colours, a wide spread), the module's visibility against Embree from
# the host's own shading points, frames in flight under synchronization validation, and the module's
# one-line refusals of bad host input.
add_test(NAME vulkan_host_writes_png
         COMMAND sh -c "rm -f \"$2\" && \"$0\" --device lavapipe --validation --size 160x90 --frames 3 --mode izb+csm \
--out \"$2\" && \"$1\" \"$2\" --min-size 160x90 --min-colors 8"
                 $<TARGET_FILE:vulkan_host> $<TARGET_FILE:png_check> ${CMAKE_CURRENT_BINARY_DIR}/vulkan_host.png)
set_tests_properties(vulkan_host_writes_png PROPERTIES LABELS gpu FAIL_REGULAR_EXPRESSION "\\[vulkan\\]")
add_executable(host_tests host/host_test.cpp support/penumbra_mask.cpp)
target_link_libraries(host_tests PRIVATE vulkan_host_app shadow_reference GTest::gtest_main)
target_include_directories(host_tests PRIVATE support)
target_strict_warnings(host_tests)
# The host path's smoke set: every refusal (capabilities per light type, mesh bounds computed on the
# device included), several lights in one record, frames in flight, a few of the input matrix's
# pairings (CPU code the sanitizer run protects); the rest of it in label gpu.
set(HOST_SMOKE_FILTER "HostBadInput.*:HostDeformed.EveryRefusalNamesItsField:HostDevice.*:HostLightCapabilities.*:HostMeshBounds.*:Modes/HostLights.*/izb_1spp:Slots/HostFramesInFlight.*/2_in_flight:\
Pairs/HostInputMatrix.*/0_*:Pairs/HostInputMatrix.*/5_*:Pairs/HostInputMatrix.*/10_*:Pairs/HostInputMatrix.*/15_*:\
Pairs/HostInputMatrix.*/17_*:Modes/HostMatchesEmbree.*/izb_csm_view0_1spp")
gtest_discover_tests(host_tests DISCOVERY_TIMEOUT 60 TEST_FILTER "${HOST_SMOKE_FILTER}"
                     PROPERTIES LABELS gpu_smoke TIMEOUT 900 ENVIRONMENT ENGINE_VALIDATION=1)
gtest_discover_tests(host_tests DISCOVERY_TIMEOUT 60 TEST_FILTER "*-${HOST_SMOKE_FILTER}"
                     PROPERTIES LABELS gpu TIMEOUT 900 ENVIRONMENT ENGINE_VALIDATION=1)
add_test(NAME syncval.host_frames_in_flight COMMAND host_tests --gtest_filter=*HostFramesInFlight.*:*HostLights.*)
set_tests_properties(syncval.host_frames_in_flight PROPERTIES LABELS syncval TIMEOUT 900 ENVIRONMENT ENGINE_SYNC_VALIDATION=1)
