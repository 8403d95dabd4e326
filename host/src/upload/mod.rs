//! Host-side upload session: configuration check, segment streaming with flow
//! control, time sync, arm and start. One code path for the in-process bus and SocketCAN.
