# Bakes the worlds test_world.lua opens into OUT (cmake -DRIDGE= -DDATA= -DOUT= -P this file).
file(MAKE_DIRECTORY ${OUT})
file(COPY ${DATA}/ramp17x9.r16 DESTINATION ${OUT})
configure_file(${DATA}/ramp16.png ${OUT}/ramp.png COPYONLY)
execute_process(COMMAND ${RIDGE} bake --heightmap ${DATA}/ramp16.png --spacing 2 --height-scale 0.5
                        --height-offset -10 --origin 100,200 --out ${OUT}/ramp.tif --quiet
                        --json ${OUT}/ramp.json
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "ridge bake ramp.tif failed (${rc})")
endif()
execute_process(COMMAND ${RIDGE} bake --generate noise --size 1025 --out ${OUT}/noise.tif --quiet
                        --json ${OUT}/noise.json
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "ridge bake noise.tif failed (${rc})")
endif()
