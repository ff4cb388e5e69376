"""Getting particles ready: firmware and ids onto boards, radios configured for the fleet."""
