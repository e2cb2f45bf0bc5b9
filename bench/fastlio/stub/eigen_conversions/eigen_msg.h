#pragma once
// Stub: FAST-LIO2 includes eigen_conversions but uses none of it; Debian 12 does not package it.
