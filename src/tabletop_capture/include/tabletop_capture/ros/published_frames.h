// Addresses of the last MultiViewFrame messages this process published. Lets an in-process
// subscriber prove that it received the very object the synchroniser published (zero-copy
// nodelet transport) rather than a copy.
#pragma once

namespace tabletop_capture {

void notePublishedFrame(const void* message);
// True if `message` is one of the last 64 frames published by this process.
bool wasPublishedFrame(const void* message);

}  // namespace tabletop_capture
