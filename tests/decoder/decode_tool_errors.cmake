# SPDX-License-Identifier: MIT
# pmz-decode (and pmz-info) on bad input: one-line error, non-zero exit, no output file; --salvage writes the
# last good level of a truncated stream and still exits non-zero.
set(out ${WORK}/out.obj)
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
file(READ ${SAMPLE} hex HEX)
string(SUBSTRING "${hex}" 0 600 hex)  # first 300 bytes: base mesh in, splits cut off
execute_process(COMMAND ${PYTHON} -c "import sys; open(sys.argv[1],'wb').write(bytes.fromhex(sys.argv[2]))"
                ${WORK}/trunc.pmz ${hex})

# pmz-decode on `file` fails, writes nothing and says `what`.
function(expect_refused file what)
  execute_process(COMMAND ${DECODE} ${file} -o ${out} RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(rc EQUAL 0 OR EXISTS ${out})
    message(FATAL_ERROR "${file}: expected failure and no output, got rc=${rc}: ${err}")
  endif()
  if(NOT err MATCHES "${what}")
    message(FATAL_ERROR "${file}: message does not say '${what}': ${err}")
  endif()
endfunction()

expect_refused(${WORK}/trunc.pmz "truncated")

execute_process(COMMAND ${DECODE} ${WORK}/trunc.pmz -o ${out} --salvage RESULT_VARIABLE rc)
if(rc EQUAL 0 OR NOT EXISTS ${out})
  message(FATAL_ERROR "--salvage: expected non-zero exit and an output file, got rc=${rc}")
endif()
file(STRINGS ${out} faces REGEX "^f ")
list(LENGTH faces nfaces)
if(nfaces LESS 1)
  message(FATAL_ERROR "--salvage wrote no faces")
endif()

file(REMOVE ${out})
execute_process(COMMAND ${DECODE} ${SAMPLE} -o ${out} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0 OR NOT EXISTS ${out})
  message(FATAL_ERROR "whole sample: expected success, got rc=${rc}")
endif()

# A damaged geometry stream with a valid CRC: framing and groups are fine, so feed() and
# finish() succeed and the damage shows only when the splits are first applied (the first
# SPLT chunk's geometry stream, its residuals, filled with 0xFF: every decision decodes as 1,
# so the first residual's bit length escapes and the escape reads 31: n = 46 > 32). Still an
# error: nothing written, exit 1; --salvage writes the last good level and still exits 1.
# pmz-info finds it with --decode (by default it does not apply the splits).
set(script [=[
import sys, zlib, struct
b = bytearray(open(sys.argv[1], 'rb').read())
def varint(p):
    v = s = 0
    while True:
        v |= (b[p] & 0x7F) << s; s += 7; p += 1
        if b[p - 1] < 0x80: return v, p
at = 8  # chunks: u8 type (3: SPLT), varint size, u32 CRC of type, size and payload, payload
while True:
    size, q = varint(at + 1)
    if b[at] == 3: break
    at = q + 4 + size
p = q + 4
end = p + size
_, p = varint(p)  # split_count
n, p = varint(p)  # the connectivity stream's size; the geometry stream is the rest
p += n
assert end > p
b[p:end] = b'\xff' * (end - p)
crc = zlib.crc32(bytes(b[at:q]) + bytes(b[q + 4:end]))
b[q:q + 4] = struct.pack('<I', crc)
open(sys.argv[2], 'wb').write(b)
]=])
file(REMOVE ${out})
execute_process(COMMAND ${PYTHON} -c "${script}" ${SAMPLE} ${WORK}/residual.pmz RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "could not make the damaged-geometry stream (rc=${rc})")
endif()
expect_refused(${WORK}/residual.pmz "residual")
execute_process(COMMAND ${DECODE} ${WORK}/residual.pmz -o ${out} --faces 100000 --salvage RESULT_VARIABLE rc)
if(NOT rc EQUAL 1 OR NOT EXISTS ${out})
  message(FATAL_ERROR "damaged geometry stream, --salvage: expected exit 1 and an output file, got rc=${rc}")
endif()
execute_process(COMMAND ${INFO} ${WORK}/residual.pmz --decode RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "residual")
  message(FATAL_ERROR "pmz-info on a damaged geometry stream: expected failure naming it, got rc=${rc}: ${err}")
endif()

# pmz-info counts the sections up to END: bytes after it (here a well-framed SPLT chunk, which
# the decoder ignores) change neither the section sizes nor the streams.
execute_process(COMMAND ${PYTHON} -c "
import sys, zlib, struct
b = open(sys.argv[1], 'rb').read()
h = bytes([3, 4]); p = bytes([1, 1, 0, 0])
open(sys.argv[2], 'wb').write(b + h + struct.pack('<I', zlib.crc32(h + p)) + p)
" ${SAMPLE} ${WORK}/trailing.pmz RESULT_VARIABLE rc)
execute_process(COMMAND ${INFO} ${SAMPLE} RESULT_VARIABLE rc1 OUTPUT_VARIABLE info1)
execute_process(COMMAND ${INFO} ${WORK}/trailing.pmz RESULT_VARIABLE rc2 OUTPUT_VARIABLE info2)
string(REGEX MATCH "splits in [^\n]*\n[^\n]*sections[^\n]*" sec1 "${info1}")
string(REGEX MATCH "splits in [^\n]*\n[^\n]*sections[^\n]*" sec2 "${info2}")
string(REGEX MATCH "streams[^\n]*" streams1 "${info1}")
string(REGEX MATCH "streams[^\n]*" streams2 "${info2}")
string(APPEND sec1 "\n${streams1}")
string(APPEND sec2 "\n${streams2}")
if(NOT rc EQUAL 0 OR NOT rc1 EQUAL 0 OR NOT rc2 EQUAL 0 OR sec1 STREQUAL "" OR NOT sec1 STREQUAL sec2)
  message(FATAL_ERROR "pmz-info with bytes after END: rc=${rc}/${rc1}/${rc2}\n${sec1}\nvs\n${sec2}")
endif()
