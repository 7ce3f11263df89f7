# png_check must reject a uniform image and an image of noise (made with ffmpeg).
#   cmake -DPNG_CHECK=path -DWORKDIR=dir -P reject_check.cmake
file(REMOVE_RECURSE ${WORKDIR})
foreach(kind blank noise)
  file(MAKE_DIRECTORY ${WORKDIR}/${kind})
endforeach()
execute_process(COMMAND ffmpeg -y -loglevel error -f lavfi -i color=c=0x23252a:s=320x180 -frames:v 1
                        ${WORKDIR}/blank/frame_0000.png RESULT_VARIABLE rc1)
execute_process(COMMAND ffmpeg -y -loglevel error -f lavfi -i nullsrc=s=320x180 -vf "geq=random(1)*255:128:128"
                        -frames:v 1 ${WORKDIR}/noise/frame_0000.png RESULT_VARIABLE rc2)
if(NOT rc1 EQUAL 0 OR NOT rc2 EQUAL 0)
  message(FATAL_ERROR "ffmpeg could not make the test images")
endif()
foreach(kind blank noise)
  execute_process(COMMAND ${PNG_CHECK} ${WORKDIR}/${kind} 1 RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${kind}: exit ${rc}\n${out}${err}")
  if(rc EQUAL 0)
    message(FATAL_ERROR "png_check accepted the ${kind} image")
  endif()
endforeach()
