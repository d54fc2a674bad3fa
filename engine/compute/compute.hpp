#pragma once
// The compute layer in one include: Device, Buffer, Kernel, Queue, Recording, Submission.
#include "compute/buffer.hpp"
#include "compute/device.hpp"
#include "compute/kernel.hpp"
#include "compute/queue.hpp"
