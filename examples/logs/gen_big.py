import json, math, sys
target = int(sys.argv[2]); out = open(sys.argv[1], "w", buffering=1<<20)
out.write(json.dumps({"type":"header","format":"pacs-log","version":1,"robot":"fr3","human":"default","constraints":"handover","meta":{"task":"handover","policy":"bench","filter":"none"}})+"\n")
x=0.6
kp=[[x,0.2,1.4],[x-0.1,0.25,1.15],[x-0.2,0.25,0.95],[x,-0.2,1.4],[x-0.1,-0.25,1.15],[x-0.2,-0.25,0.95],[x,0,1.45],[x,0,0.95],[x,0,1.65]]
kps=json.dumps(kp,separators=(",",":"))
Q=[0.0,-0.785,0.0,-2.356,0.0,1.571,0.785]
size=0; i=0
while size < target:
    t=i*1e-3
    chunk=[]
    for k in range(1000):
        t=(i)*1e-3
        if i%33==0:
            chunk.append('{"type":"human","t":%r,"t_meas":%r,"positions":%s}\n'%(t,t,kps))
        q=[Q[j]+0.3*math.sin((0.5+0.1*j)*t) for j in range(7)]
        dq=[0.3*(0.5+0.1*j)*math.cos((0.5+0.1*j)*t) for j in range(7)]
        chunk.append('{"type":"robot","t":%r,"q":[%s],"dq":[%s]}\n'%(t,",".join("%.6f"%v for v in q),",".join("%.6f"%v for v in dq)))
        i+=1
    s="".join(chunk); out.write(s); size+=len(s)
out.close(); print(i, "samples", size, "bytes")
