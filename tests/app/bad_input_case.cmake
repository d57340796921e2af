# One case of the bad-input corpus (tests/data/bad/*.cases), run by CTest as
#   cmake -DEXE=<mbi> -DBAD=<tests/data/bad> -DWORK=<fresh folder> -DEXIT=<code>
#         -DOUTPUTS=none|any -DMESSAGE=<regex> -DARGS=<;-list> -P bad_input_case.cmake
# Placeholders in ARGS: @BAD@ the corpus folder, @OUT@ an empty folder for this case,
# @FIFO@ a named pipe made in @OUT@, @DIR@ an (empty) directory made in @OUT@, @FILE@ a
# regular file made in @OUT@ (so @FILE@/x cannot be created), @CHR@ a character device made in
# @OUT@ with the numbers of /dev/null (mknod: the case is skipped where that is not allowed),
# @LOCKED@ an empty directory made in @OUT@ that another process (flock(1)) holds locked while
# mbi runs (io::FolderLock).
# An argument @FSIZE_LIMIT=N@ (anywhere; removed) runs mbi with a file-size limit of N KiB
# (ulimit -f, SIGXFSZ ignored): a write past N KiB fails (EFBIG) as on a full disk, without
# mounting one; the limit applies to mbi alone (set in a shell that then becomes mbi), never to
# the X server or its runner. -DXVFB=ON runs mbi under a fresh Xvfb server (the viewer's cases:
# with_xvfb.sh, whose exit status is mbi's alone).
# Checks: the exit code, stderr matching MESSAGE, no crash (sanitizer reports fail the case), no
# output left under @OUT@ when OUTPUTS is none, every corpus file unchanged (inputs are never
# modified), and @FIFO@ and @CHR@ still what they were (never replaced by a file).
cmake_minimum_required(VERSION 3.25)
foreach(v EXE BAD WORK EXIT OUTPUTS MESSAGE)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "bad_input_case.cmake: -D${v}= missing")
  endif()
endforeach()

file(REMOVE_RECURSE "${WORK}")
set(out "${WORK}/out")
file(MAKE_DIRECTORY "${out}")
set(setup_made "")
set(args "")
set(limit "")
foreach(a IN LISTS ARGS)
  if(a MATCHES "^@FSIZE_LIMIT=([0-9]+)@$")
    set(limit ${CMAKE_MATCH_1})
    continue()
  endif()
  if(a MATCHES "@CHR@" AND NOT EXISTS "${out}/null")
    execute_process(COMMAND mknod "${out}/null" c 1 3 RESULT_VARIABLE rv ERROR_QUIET)
    if(NOT rv EQUAL 0)
      message(STATUS "SKIP: mknod is not allowed here (no character device for @CHR@)")
      return()
    endif()
    list(APPEND setup_made "${out}/null")
  endif()
  if(a MATCHES "@FIFO@" AND NOT EXISTS "${out}/in.fifo")
    execute_process(COMMAND mkfifo "${out}/in.fifo" RESULT_VARIABLE rv)
    if(NOT rv EQUAL 0)
      message(FATAL_ERROR "cannot make a FIFO")
    endif()
    list(APPEND setup_made "${out}/in.fifo")
  endif()
  if(a MATCHES "@DIR@" AND NOT EXISTS "${out}/a-dir")
    file(MAKE_DIRECTORY "${out}/a-dir")
    list(APPEND setup_made "${out}/a-dir")
  endif()
  if(a MATCHES "@LOCKED@" AND NOT EXISTS "${out}/locked")
    file(MAKE_DIRECTORY "${out}/locked")
    list(APPEND setup_made "${out}/locked")
  endif()
  if(a MATCHES "@FILE@" AND NOT EXISTS "${out}/a-file")
    file(WRITE "${out}/a-file" "not a folder\n")
    list(APPEND setup_made "${out}/a-file")
  endif()
  string(REPLACE "@BAD@" "${BAD}" a "${a}")
  string(REPLACE "@FIFO@" "${out}/in.fifo" a "${a}")
  string(REPLACE "@DIR@" "${out}/a-dir" a "${a}")
  string(REPLACE "@FILE@" "${out}/a-file" a "${a}")
  string(REPLACE "@CHR@" "${out}/null" a "${a}")
  string(REPLACE "@LOCKED@" "${out}/locked" a "${a}")
  string(REPLACE "@OUT@" "${out}" a "${a}")
  list(APPEND args "${a}")
endforeach()

# Fingerprint of the corpus before the run.
file(GLOB_RECURSE corpus LIST_DIRECTORIES false "${BAD}/*")
set(before "")
foreach(f IN LISTS corpus)
  file(SHA256 "${f}" h)
  string(APPEND before "${f} ${h}\n")
endforeach()

set(command "${EXE}" ${args})
if(limit)
  math(EXPR blocks "${limit} * 2")  # POSIX ulimit -f counts blocks of 512 bytes
  set(command sh -c "ulimit -f ${blocks} && trap '' XFSZ && exec \"\$@\"" sh ${command})
endif()
if(XVFB)
  set(command sh ${CMAKE_CURRENT_LIST_DIR}/with_xvfb.sh ${command})
endif()
if(ARGS MATCHES "@LOCKED@")
  # a pipeline: flock holds the folder and says so, then mbi starts; the holder ends on SIGPIPE
  # once mbi has gone
  execute_process(
    COMMAND flock "${out}/locked" sh -c "echo locked; while sleep 0.1; do echo; done"
    COMMAND sh -c "read held && exec \"$0\" \"$@\"" ${command}
    WORKING_DIRECTORY "${WORK}"
    RESULT_VARIABLE code OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr TIMEOUT 60)
else()
  execute_process(COMMAND ${command}
    WORKING_DIRECTORY "${WORK}"
    RESULT_VARIABLE code OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr TIMEOUT 60)
endif()

set(failures "")
if(NOT code STREQUAL "${EXIT}")
  string(APPEND failures "exit code '${code}', expected ${EXIT}\n")
endif()
if(NOT stderr MATCHES "${MESSAGE}")
  string(APPEND failures "stderr does not match '${MESSAGE}'\n")
endif()
if(stderr MATCHES "AddressSanitizer|UndefinedBehaviorSanitizer|runtime error:|LeakSanitizer")
  string(APPEND failures "sanitizer report\n")
endif()
if(OUTPUTS STREQUAL "none")
  file(GLOB_RECURSE left LIST_DIRECTORIES true "${out}/*")
  foreach(f IN LISTS left)
    list(FIND setup_made "${f}" made)
    if(made EQUAL -1)
      string(APPEND failures "output left behind: ${f}\n")
    endif()
  endforeach()
endif()
if(EXISTS "${out}/in.fifo")
  execute_process(COMMAND test -p "${out}/in.fifo" RESULT_VARIABLE rv)
  if(NOT rv EQUAL 0)
    string(APPEND failures "the FIFO was replaced\n")
  endif()
endif()
if(EXISTS "${out}/null")
  execute_process(COMMAND test -c "${out}/null" RESULT_VARIABLE rv)
  if(NOT rv EQUAL 0)
    string(APPEND failures "the character device was replaced\n")
  endif()
endif()
set(after "")
foreach(f IN LISTS corpus)
  file(SHA256 "${f}" h)
  string(APPEND after "${f} ${h}\n")
endforeach()
if(NOT before STREQUAL after)
  string(APPEND failures "a corpus file was modified\n")
endif()

if(failures)
  list(JOIN args " " shown)
  message(FATAL_ERROR "mbi ${shown}\n${failures}--- stderr ---\n${stderr}--- stdout ---\n${stdout}")
endif()
