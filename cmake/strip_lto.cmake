# Run at install time (CMakeLists.txt): the installed static libraries keep their machine code
# only. Fat LTO objects also carry GIMPLE for the project's own LTO links; in an installed archive
# it would make every consumer's link run link-time optimisation over the library.
foreach(part lidarsurf lidarsurf_sim lidarsurf_eval lidarsurf_viz)
  set(archive "$ENV{DESTDIR}${CMAKE_INSTALL_PREFIX}/${LIDARSURF_LIBDIR}/lib${part}.a")
  execute_process(COMMAND "${LIDARSURF_OBJCOPY}" -R ".gnu.lto_*" -R ".gnu.debuglto_*" -N __gnu_lto_v1 -N __gnu_lto_slim
                          --enable-deterministic-archives "${archive}" RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "objcopy could not strip the LTO sections of ${archive}: ${err}")
  endif()
  message(STATUS "Stripped the LTO sections: ${archive}")
endforeach()
