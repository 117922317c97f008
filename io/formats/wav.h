#pragma once
// WAV audio through libsndfile.
//
// ReadWav accepts whatever libsndfile reads as audio (WAV PCM 8/16/24/32-bit,
// float, WAVE_FORMAT_EXTENSIBLE, and also AIFF/FLAC/... when given one) and
// returns float samples, interleaved, integers scaled by 1/2^(bits-1) (16-bit:
// sample / 32768, so -32768 -> -1.0). The file is read in blocks until the end,
// never by trusting the declared length, so a header claiming more frames than
// the file holds gives the frames present. Errors: csw::IoError when the file
// cannot be opened, csw::ParseError (file; sample index for bad samples) when
// libsndfile refuses it, it declares no rate / no channels / more than 4096
// channels, or a float file holds NaN or infinite samples.
//
// WriteWav writes RIFF WAV: bits == 16 gives PCM 16-bit, samples clamped to
// [-1, 1) and rounded to the nearest multiple of 1/32768 (so a 16-bit file read
// by ReadWav writes back bit-exact); bits == 32 gives 32-bit IEEE float.
// Throws InvalidInput for other bit depths, a non-integer or non-positive
// rate, channels < 1, a sample count that is not a multiple of channels, or
// non-finite samples; IoError when the file cannot be written.
#include <string>

#include "core/take.h"

namespace csw {

Audio ReadWav(const std::string& path);
void WriteWav(const std::string& path, const Audio& audio, int bits = 16);

}  // namespace csw
