// Private: a PNG file's chunk structure checked before the image library decodes it.
#pragma once

#include <string>

#include "ridgeline/result.h"

namespace ridgeline::io::detail {

/// When `path` starts with the PNG signature, walks its chunks from the first to IEND without
/// decoding them: every chunk must lie wholly inside the file and match its CRC-32. libpng
/// reports a truncated or corrupt file by printing its own line on stderr before the error
/// reaches us, and OpenImageIO's message then repeats the read error; refusing such files here
/// gives one message naming the chunk and the byte offset. Files without the signature pass
/// (other readers check them). `name` prefixes the message ("heightmap 'a.png'").
Status check_png_chunks(const std::string& path, const std::string& name);

}  // namespace ridgeline::io::detail
