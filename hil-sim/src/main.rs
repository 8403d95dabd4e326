fn main() {
    eprintln!("triquint-sim: the SocketCAN simulator is not built yet");
    std::process::exit(4);
}
