import cantools, sys
db = cantools.database.load_file('docs/triquint.dbc')
n=0
for line in open('testdata/protocol/golden.txt'):
    if line.startswith('#'): continue
    label, idh, kind, hexs = [x.strip() for x in line.split('|')]
    data = bytes.fromhex(hexs)
    m = db.get_message_by_frame_id(int(idh,16))
    if kind=='F' and len(data) < m.length: data = data + bytes(m.length-len(data))
    d = m.decode(data)
    n+=1
    if n in (1,9,16,17,18,36,37): print(label, m.name, m.is_fd, d)
print("decoded", n)
